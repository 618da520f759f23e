#include "client/io/read_volume.h"

#include "absl/strings/match.h"
#include "client/io/io_error.h"
#include "client/io/metaimage_reader.h"
#include "client/io/nifti_reader.h"
#include "client/io/nrrd_reader.h"
#include "client/io/vti_reader.h"
#include "client/io/vtk_legacy_format.h"

namespace tetrefine::io {

absl::StatusOr<VolumeFile> ReadVolume(const std::string& path) {
  const auto has = [&path](absl::string_view suffix) {
    return absl::EndsWithIgnoreCase(path, suffix);
  };
  if (has(".nii") || has(".nii.gz") || has(".hdr") || has(".hdr.gz")) return ReadNifti(path);
  if (has(".nrrd") || has(".nhdr")) return ReadNrrd(path);
  if (has(".mha") || has(".mhd")) return ReadMetaImage(path);
  if (has(".vti")) return ReadVti(path);
  if (has(".pvti")) return ReadPvti(path);
  if (has(".vtk")) return ReadVtkLegacyImage(path);  // a mesh .vtk says so
  if (has(".img") || has(".img.gz")) {
    return FileError(path, "an .img file holds only samples: read its .hdr");
  }
  // DICOM (.dcm or extension-less series) is out of scope: a series needs slice sorting and
  // per-vendor geometry rules. Convert it first, e.g. with dcm2niix, and read the NIfTI.
  return FileError(
      path,
      "unknown extension for a volume: expected .nii, .nii.gz, .hdr, .nrrd, .nhdr, "
      ".mha, .mhd, .vti, .pvti or .vtk (DICOM is not read: convert it to NIfTI with dcm2niix)");
}

}  // namespace tetrefine::io
