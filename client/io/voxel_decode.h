#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "absl/strings/string_view.h"
#include "client/io/byte_order.h"
#include "core/voxel_type.h"

namespace tetrefine::io {

// The sample types volume files store and the readers take: core's six VoxelTypes, plus the
// integer types a Volume does not have, which DecodeVoxels widens to one without changing any
// value, as the Python client (python/tetrefine/_requests.py, _wire_voxel_type) widens a numpy
// array: int8 to int16; uint32, int64 and uint64 to int32 when every value fits it, else to
// float64 when every magnitude is at most 2^53 (float64's exact integers), else refused.
enum class StoredType : uint8_t {
  kUint8,
  kInt16,
  kUint16,
  kInt32,
  kFloat32,
  kFloat64,
  kInt8,
  kUint32,
  kInt64,
  kUint64,
};

// The StoredType of core's `type` (the same type).
StoredType StoredTypeOf(VoxelType type);

// Bytes per sample of `type`: 1, 2, 4 or 8.
size_t StoredSize(StoredType type);

// Lower-case name ("int8", "uint32", ...; core's names for its types), as in messages.
absl::string_view StoredTypeName(StoredType type);

// Samples ready for Volume::Create: little-endian values of `type`, x fastest.
struct DecodedVoxels {
  VoxelType type = VoxelType::kFloat64;
  std::vector<std::byte> data;
};

// Converts `count` stored samples of `type` in `order` to Volume storage. When the scaling
// y = slope * x + inter is not the identity, the result holds scaled values: float32 for sources
// of at most 16 bits and float32 sources (their values fit its 24-bit mantissa), float64
// otherwise (a 64-bit integer beyond 2^53 is rounded to float64 before the scaling, as every
// scaled value is rounded to the result's precision). A slope of 0 means "no scaling", as in
// NIfTI. Unscaled samples keep a core type and widen exactly otherwise (StoredType); uint32,
// int64 or uint64 samples that neither int32 nor float64 holds exactly are an InvalidArgument
// error naming the type and the largest magnitude. `bytes` must hold exactly
// count * StoredSize(type) bytes.
absl::StatusOr<DecodedVoxels> DecodeVoxels(absl::string_view bytes, StoredType type,
                                           ByteOrder order, double slope, double inter);

// The error DecodeVoxels gives for samples of `type` whose largest magnitude, `magnitude` (as
// text), does not fit int32 and would round in float64; for readers that widen values they hold
// as numbers (an ASCII file's) by the same rule.
absl::Status TooWideError(StoredType type, absl::string_view magnitude);

}  // namespace tetrefine::io
