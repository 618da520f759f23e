#include "bench/support/field_volume.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>

namespace tetrefine::bench {
namespace {

template <typename T>
void Put(std::vector<std::byte>& out, size_t i, double v) {
  T t;
  if constexpr (std::is_integral_v<T>) {
    const double lo = static_cast<double>(std::numeric_limits<T>::min());
    const double hi = static_cast<double>(std::numeric_limits<T>::max());
    t = static_cast<T>(std::clamp(std::round(v), lo, hi));
  } else {
    t = static_cast<T>(v);
  }
  std::memcpy(out.data() + i * sizeof(T), &t, sizeof(T));
}

}  // namespace

Volume VolumeFromValues(const GridGeometry& grid, VoxelType type,
                        const std::vector<double>& values) {
  std::vector<std::byte> bytes(values.size() * VoxelSize(type));
  for (size_t i = 0; i < values.size(); ++i) {
    switch (type) {
      case VoxelType::kUint8:
        Put<uint8_t>(bytes, i, values[i]);
        break;
      case VoxelType::kInt16:
        Put<int16_t>(bytes, i, values[i]);
        break;
      case VoxelType::kUint16:
        Put<uint16_t>(bytes, i, values[i]);
        break;
      case VoxelType::kInt32:
        Put<int32_t>(bytes, i, values[i]);
        break;
      case VoxelType::kFloat32:
        Put<float>(bytes, i, values[i]);
        break;
      case VoxelType::kFloat64:
        Put<double>(bytes, i, values[i]);
        break;
    }
  }
  absl::StatusOr<Volume> v = Volume::CreateWhole(grid, type, std::move(bytes));
  if (!v.ok()) {
    std::fprintf(stderr, "VolumeFromValues: %s\n", std::string(v.status().message()).c_str());
    std::abort();
  }
  return *std::move(v);
}

}  // namespace tetrefine::bench
