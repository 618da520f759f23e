#include "client/io/read_volume.h"

#include <filesystem>

#include "absl/strings/match.h"
#include "client/io/dicom_series.h"
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
  // A DICOM series: its directory, or one of its files (.dcm, or named by the scanner without an
  // extension and recognised by the magic).
  if (IsDicomPath(path)) return ReadDicomSeries(path);
  // A mistyped series directory has no extension either: say it is missing (a sweep got
  // "unknown extension" for one).
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) {
    return FileError(path, "cannot open: No such file or directory");
  }
  return FileError(path,
                   "unknown extension for a volume: expected .nii, .nii.gz, .hdr, .nrrd, .nhdr, "
                   ".mha, .mhd, .vti, .pvti, .vtk, or a DICOM series (its directory or one of "
                   "its files)");
}

}  // namespace tetrefine::io
