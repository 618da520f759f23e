#pragma once

#include <string>

#include "absl/status/statusor.h"
#include "client/io/volume_file.h"

namespace tetrefine::io {

// Reads a volume, choosing the format from the extension (case-insensitive):
//   .nii .nii.gz .hdr .hdr.gz  NIfTI-1/2   (ReadNifti)
//   .nrrd .nhdr                NRRD        (ReadNrrd)
//   .mha .mhd                  MetaImage   (ReadMetaImage)
//   .vti .pvti                 VTK XML image, parallel image (ReadVti, ReadPvti)
//   .vtk                       legacy VTK STRUCTURED_POINTS (ReadVtkLegacyImage)
// Any other extension is an "unknown extension" error naming the file. The result is in world
// RAS mm (see VolumeFile).
absl::StatusOr<VolumeFile> ReadVolume(const std::string& path);

}  // namespace tetrefine::io
