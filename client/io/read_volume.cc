#include "client/io/read_volume.h"

#include <filesystem>

#include "absl/strings/match.h"
#include "absl/strings/str_cat.h"
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
    // The samples of a .hdr/.img pair: read through their header, as nibabel and ITK read a
    // pair named by either half (an outside review, 2026-11-28, found `info x.img` refused).
    // The header ReadNifti pairs with this .img (ImagePathFor): the same stem and case, .gz when
    // the samples are gzipped.
    const bool gz = has(".img.gz");
    const size_t stem = path.size() - (gz ? 7 : 4);
    const bool upper = path[stem + 1] == 'I';
    const std::string header = absl::StrCat(path.substr(0, stem), upper ? ".HDR" : ".hdr",
                                            gz ? path.substr(stem + 4) : "");
    std::error_code ec;
    if (std::filesystem::exists(header, ec)) return ReadNifti(header);
    return FileError(path, absl::StrCat("an .img file holds only samples, and its header ", header,
                                        " is missing"));
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
