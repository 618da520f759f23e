#pragma once

#include <string>

#include "absl/status/statusor.h"
#include "client/io/volume_file.h"

namespace tetrefine::io {

// Reads a 3D NIfTI-1 or NIfTI-2 volume: .nii, .nii.gz, or a .hdr/.img pair (each optionally
// gzipped), either byte order. Sample types: uint8, int16, uint16, int32, float32, float64, and
// int8, uint32, int64, uint64 widened exactly (DecodeVoxels: as the Python client widens numpy
// arrays); others are an Unimplemented error naming the type. scl_slope/scl_inter are applied
// when they are not the identity (the volume then holds float32 or float64 values). Frame: world
// RAS mm, see VolumeFile. Dimensions beyond the third must be 1 (a 4D series is refused).
absl::StatusOr<VolumeFile> ReadNifti(const std::string& path);

}  // namespace tetrefine::io
