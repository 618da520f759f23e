#pragma once

#include <cstddef>
#include <vector>

#include "absl/status/statusor.h"
#include "absl/strings/string_view.h"
#include "client/io/byte_order.h"
#include "core/voxel_type.h"

namespace tetrefine::io {

// Samples ready for Volume::Create: little-endian values of `type`, x fastest.
struct DecodedVoxels {
  VoxelType type = VoxelType::kFloat64;
  std::vector<std::byte> data;
};

// Converts `count` stored samples of `type` in `order` to Volume storage. When the scaling
// y = slope * x + inter is not the identity, the result holds scaled values: float32 for sources
// of at most 16 bits and float32 sources (their values fit its 24-bit mantissa), float64
// otherwise. A slope of 0 means "no scaling", as in NIfTI. `bytes` must hold exactly
// count * VoxelSize(type) bytes.
absl::StatusOr<DecodedVoxels> DecodeVoxels(absl::string_view bytes, VoxelType type, ByteOrder order,
                                           double slope, double inter);

}  // namespace tetrefine::io
