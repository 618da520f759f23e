#include "client/io/voxel_decode.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <optional>
#include <type_traits>
#include <utility>

#include "absl/status/status.h"
#include "absl/strings/str_cat.h"

namespace tetrefine::io {
namespace {

// float64 holds every integer of magnitude at most 2^53 exactly, and not 2^53 + 1.
constexpr uint64_t kFloat64ExactInteger = uint64_t{1} << 53;

std::optional<VoxelType> CoreType(StoredType type) {
  switch (type) {
    case StoredType::kUint8:
      return VoxelType::kUint8;
    case StoredType::kInt16:
      return VoxelType::kInt16;
    case StoredType::kUint16:
      return VoxelType::kUint16;
    case StoredType::kInt32:
      return VoxelType::kInt32;
    case StoredType::kFloat32:
      return VoxelType::kFloat32;
    case StoredType::kFloat64:
      return VoxelType::kFloat64;
    case StoredType::kInt8:
    case StoredType::kUint32:
    case StoredType::kInt64:
    case StoredType::kUint64:
      break;
  }
  return std::nullopt;
}

// Calls f(T{}) with T the C++ type of `type`.
template <typename F>
void Dispatch(StoredType type, F&& f) {
  switch (type) {
    case StoredType::kUint8:
      return f(uint8_t{});
    case StoredType::kInt16:
      return f(int16_t{});
    case StoredType::kUint16:
      return f(uint16_t{});
    case StoredType::kInt32:
      return f(int32_t{});
    case StoredType::kFloat32:
      return f(float{});
    case StoredType::kFloat64:
      return f(double{});
    case StoredType::kInt8:
      return f(int8_t{});
    case StoredType::kUint32:
      return f(uint32_t{});
    case StoredType::kInt64:
      return f(int64_t{});
    case StoredType::kUint64:
      return f(uint64_t{});
  }
}

// Every sample of `bytes` (In in `order`) as an Out, little-endian, into `out`. `convert` maps
// one In to one Out.
template <typename In, typename Out, typename Convert>
void ConvertAll(absl::string_view bytes, ByteOrder order, std::vector<std::byte>& out,
                Convert convert) {
  const size_t count = bytes.size() / sizeof(In);
  out.resize(count * sizeof(Out));
  for (size_t i = 0; i < count; ++i) {
    const Out y = convert(LoadAs<In>(bytes, i * sizeof(In), order));
    // Volume storage is little-endian; core asserts a little-endian host.
    std::memcpy(out.data() + i * sizeof(Out), &y, sizeof(Out));
  }
}

template <typename Out>
void ScaleAll(StoredType type, absl::string_view bytes, ByteOrder order, double slope, double inter,
              std::vector<std::byte>& out) {
  Dispatch(type, [&](auto in) {
    using In = decltype(in);
    ConvertAll<In, Out>(bytes, order, out, [&](In x) {
      return static_cast<Out>(slope * static_cast<double>(x) + inter);
    });
  });
}

// The largest magnitude of the samples (as uint64, exact for every int64 and uint64) and
// whether every one lies in [INT32_MIN, INT32_MAX].
template <typename In>
std::pair<uint64_t, bool> MagnitudeAndInt32(absl::string_view bytes, ByteOrder order) {
  static_assert(std::is_integral_v<In>);
  const size_t count = bytes.size() / sizeof(In);
  if (count == 0) return {0, true};
  In lo = std::numeric_limits<In>::max(), hi = std::numeric_limits<In>::min();
  for (size_t i = 0; i < count; ++i) {
    const In x = LoadAs<In>(bytes, i * sizeof(In), order);
    lo = std::min(lo, x);
    hi = std::max(hi, x);
  }
  // |lo| computed in uint64: defined also for INT64_MIN.
  uint64_t lo_magnitude = 0;
  if constexpr (std::is_signed_v<In>) {
    if (lo < 0) lo_magnitude = uint64_t{0} - static_cast<uint64_t>(static_cast<int64_t>(lo));
  }
  const uint64_t hi_magnitude = static_cast<uint64_t>(std::max<In>(hi, 0));
  // [-2^31, 2^31 - 1], as the Python client's -2**31 <= lo and hi < 2**31.
  const bool int32 = lo_magnitude <= (uint64_t{1} << 31) && hi_magnitude < (uint64_t{1} << 31);
  return {std::max(lo_magnitude, hi_magnitude), int32};
}

// Unscaled uint32, int64 or uint64 samples: int32 when every value fits, float64 when every
// magnitude is at most 2^53; an error otherwise.
template <typename In>
absl::Status WidenWide(StoredType type, absl::string_view bytes, ByteOrder order,
                       DecodedVoxels& result) {
  const auto [magnitude, fits_int32] = MagnitudeAndInt32<In>(bytes, order);
  if (fits_int32) {
    result.type = VoxelType::kInt32;
    ConvertAll<In, int32_t>(bytes, order, result.data,
                            [](In x) { return static_cast<int32_t>(x); });
    return absl::OkStatus();
  }
  if (magnitude > kFloat64ExactInteger) return TooWideError(type, absl::StrCat(magnitude));
  result.type = VoxelType::kFloat64;
  ConvertAll<In, double>(bytes, order, result.data, [](In x) { return static_cast<double>(x); });
  return absl::OkStatus();
}

}  // namespace

StoredType StoredTypeOf(VoxelType type) {
  switch (type) {
    case VoxelType::kUint8:
      return StoredType::kUint8;
    case VoxelType::kInt16:
      return StoredType::kInt16;
    case VoxelType::kUint16:
      return StoredType::kUint16;
    case VoxelType::kInt32:
      return StoredType::kInt32;
    case VoxelType::kFloat32:
      return StoredType::kFloat32;
    case VoxelType::kFloat64:
      break;
  }
  return StoredType::kFloat64;
}

size_t StoredSize(StoredType type) {
  size_t size = 0;
  Dispatch(type, [&](auto x) { size = sizeof(x); });
  return size;
}

absl::string_view StoredTypeName(StoredType type) {
  if (const std::optional<VoxelType> core = CoreType(type)) {
    const std::string_view name = VoxelTypeName(*core);
    return absl::string_view(name.data(), name.size());
  }
  switch (type) {
    case StoredType::kInt8:
      return "int8";
    case StoredType::kUint32:
      return "uint32";
    case StoredType::kInt64:
      return "int64";
    case StoredType::kUint64:
      return "uint64";
    default:
      break;
  }
  return "unknown";
}

absl::Status TooWideError(StoredType type, absl::string_view magnitude) {
  return absl::InvalidArgumentError(
      absl::StrCat(StoredTypeName(type), " values up to ", magnitude,
                   " do not fit int32 and would round in float64; rescale them first"));
}

absl::StatusOr<DecodedVoxels> DecodeVoxels(absl::string_view bytes, StoredType type,
                                           ByteOrder order, double slope, double inter) {
  const size_t width = StoredSize(type);
  if (bytes.size() % width != 0) {
    return absl::InvalidArgumentError(absl::StrCat(bytes.size(),
                                                   " voxel bytes is not a whole number of ", width,
                                                   "-byte ", StoredTypeName(type), " samples"));
  }
  if (!std::isfinite(slope) || !std::isfinite(inter)) {
    return absl::InvalidArgumentError(
        absl::StrCat("intensity scaling is not finite (slope ", slope, ", intercept ", inter, ")"));
  }
  DecodedVoxels result;
  const bool scaled = slope != 0.0 && (slope != 1.0 || inter != 0.0);
  if (scaled) {
    const bool narrow = width <= 2 || type == StoredType::kFloat32;
    result.type = narrow ? VoxelType::kFloat32 : VoxelType::kFloat64;
    if (narrow) {
      ScaleAll<float>(type, bytes, order, slope, inter, result.data);
    } else {
      ScaleAll<double>(type, bytes, order, slope, inter, result.data);
    }
    return result;
  }
  if (const std::optional<VoxelType> core = CoreType(type)) {
    result.type = *core;
    result.data.resize(bytes.size());
    std::memcpy(result.data.data(), bytes.data(), bytes.size());
    if (order != ByteOrder::kLittle) SwapEachElement(result.data.data(), bytes.size(), width);
    return result;
  }
  absl::Status widened = absl::OkStatus();
  switch (type) {
    case StoredType::kInt8:
      result.type = VoxelType::kInt16;
      ConvertAll<int8_t, int16_t>(bytes, order, result.data,
                                  [](int8_t x) { return static_cast<int16_t>(x); });
      break;
    case StoredType::kUint32:
      widened = WidenWide<uint32_t>(type, bytes, order, result);
      break;
    case StoredType::kInt64:
      widened = WidenWide<int64_t>(type, bytes, order, result);
      break;
    case StoredType::kUint64:
      widened = WidenWide<uint64_t>(type, bytes, order, result);
      break;
    default:
      break;
  }
  if (!widened.ok()) return widened;
  return result;
}

}  // namespace tetrefine::io
