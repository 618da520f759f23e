#include "core/voxel_type.h"

#include <array>
#include <utility>

namespace tetrefine {
namespace {

constexpr std::array<std::pair<VoxelType, std::string_view>, 6> kNames = {{
    {VoxelType::kUint8, "uint8"},
    {VoxelType::kInt16, "int16"},
    {VoxelType::kUint16, "uint16"},
    {VoxelType::kInt32, "int32"},
    {VoxelType::kFloat32, "float32"},
    {VoxelType::kFloat64, "float64"},
}};

}  // namespace

size_t VoxelSize(VoxelType type) {
  switch (type) {
    case VoxelType::kUint8:
      return 1;
    case VoxelType::kInt16:
    case VoxelType::kUint16:
      return 2;
    case VoxelType::kInt32:
    case VoxelType::kFloat32:
      return 4;
    case VoxelType::kFloat64:
      return 8;
  }
  return 0;
}

std::string_view VoxelTypeName(VoxelType type) {
  for (const auto& [t, name] : kNames) {
    if (t == type) return name;
  }
  return "unknown";
}

std::optional<VoxelType> VoxelTypeFromName(std::string_view name) {
  for (const auto& [t, n] : kNames) {
    if (n == name) return t;
  }
  return std::nullopt;
}

}  // namespace tetrefine
