#pragma once

#include <cstddef>
#include <vector>

#include "absl/status/statusor.h"
#include "absl/strings/string_view.h"
#include "client/io/volume_file.h"
#include "core/volume.h"
#include "core/voxel_type.h"

namespace tetrefine::io {

// Relative size below which an off-diagonal affine entry counts as zero. Affines computed from
// float32 quaternions carry rounding of about 1e-7 of the column length; real obliquity is far
// larger (a 0.1 degree tilt is 1.7e-3).
inline constexpr double kObliqueTolerance = 1e-5;

// The voxel sizes (affine column lengths) a volume file may have, in mm: 1 pm to 1000 km, far
// beyond any scanner or microscope, and far from the subnormal and overflowing products at which
// the geometry stops round-tripping exactly.
inline constexpr double kMinVoxelMm = 1e-9;
inline constexpr double kMaxVoxelMm = 1e9;
// How far from the world origin, in the voxels that step along a world axis, a grid may reach
// along it: 2^44 (float64 then places samples to within 0.004 of a voxel; 1 pm voxels 10 mm from
// the origin are 2^33).
inline constexpr double kMaxVoxelsFromOrigin = 17592186044416.0;

// Builds the VolumeFile for samples stored in index order (x fastest) with index-to-world (RAS
// mm) transform `affine`, following the frame rules documented on VolumeFile: flips axes with a
// negative scale when the affine is diagonal up to signs, otherwise keeps the samples and puts the
// normalised columns into the grid's direction. `data` holds dims.prod() little-endian samples of
// `type`. Errors (naming `path`): a non-finite entry, a zero column, a column length outside
// [kMinVoxelMm, kMaxVoxelMm] (naming the axis), a corner more than kMaxVoxelsFromOrigin
// voxels from the world origin, a singular direction.
absl::StatusOr<VolumeFile> PlaceOnGrid(absl::string_view path, const Affine& affine,
                                       const Index3& dims, VoxelType type,
                                       std::vector<std::byte> data);

}  // namespace tetrefine::io
