#include "client/io/voxel_decode.h"

#include <cmath>
#include <cstring>

#include "absl/status/status.h"
#include "absl/strings/str_cat.h"

namespace tetrefine::io {
namespace {

template <typename In, typename Out>
void ScaleAll(absl::string_view bytes, ByteOrder order, double slope, double inter,
              std::vector<std::byte>& out) {
  const size_t count = bytes.size() / sizeof(In);
  out.resize(count * sizeof(Out));
  for (size_t i = 0; i < count; ++i) {
    const double x = static_cast<double>(LoadAs<In>(bytes, i * sizeof(In), order));
    const Out y = static_cast<Out>(slope * x + inter);
    // Volume storage is little-endian; core asserts a little-endian host.
    std::memcpy(out.data() + i * sizeof(Out), &y, sizeof(Out));
  }
}

template <typename Out>
void ScaleFrom(VoxelType type, absl::string_view bytes, ByteOrder order, double slope, double inter,
               std::vector<std::byte>& out) {
  switch (type) {
    case VoxelType::kUint8:
      return ScaleAll<uint8_t, Out>(bytes, order, slope, inter, out);
    case VoxelType::kInt16:
      return ScaleAll<int16_t, Out>(bytes, order, slope, inter, out);
    case VoxelType::kUint16:
      return ScaleAll<uint16_t, Out>(bytes, order, slope, inter, out);
    case VoxelType::kInt32:
      return ScaleAll<int32_t, Out>(bytes, order, slope, inter, out);
    case VoxelType::kFloat32:
      return ScaleAll<float, Out>(bytes, order, slope, inter, out);
    case VoxelType::kFloat64:
      return ScaleAll<double, Out>(bytes, order, slope, inter, out);
  }
}

}  // namespace

absl::StatusOr<DecodedVoxels> DecodeVoxels(absl::string_view bytes, VoxelType type, ByteOrder order,
                                           double slope, double inter) {
  const size_t width = VoxelSize(type);
  if (bytes.size() % width != 0) {
    return absl::InvalidArgumentError(
        absl::StrCat(bytes.size(), " voxel bytes is not a whole number of ", width, "-byte ",
                     std::string(VoxelTypeName(type)), " samples"));
  }
  if (!std::isfinite(slope) || !std::isfinite(inter)) {
    return absl::InvalidArgumentError(
        absl::StrCat("intensity scaling is not finite (slope ", slope, ", intercept ", inter, ")"));
  }
  DecodedVoxels result;
  const bool scaled = slope != 0.0 && (slope != 1.0 || inter != 0.0);
  if (!scaled) {
    result.type = type;
    result.data.resize(bytes.size());
    std::memcpy(result.data.data(), bytes.data(), bytes.size());
    if (order != ByteOrder::kLittle) SwapEachElement(result.data.data(), bytes.size(), width);
    return result;
  }
  const bool narrow = width <= 2 || type == VoxelType::kFloat32;
  result.type = narrow ? VoxelType::kFloat32 : VoxelType::kFloat64;
  if (narrow) {
    ScaleFrom<float>(type, bytes, order, slope, inter, result.data);
  } else {
    ScaleFrom<double>(type, bytes, order, slope, inter, result.data);
  }
  return result;
}

}  // namespace tetrefine::io
