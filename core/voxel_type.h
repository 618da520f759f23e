#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string_view>

namespace tetrefine {

// Storage type of voxel values. Volumes keep their native type (an int16 CT stays 2 bytes a
// voxel); sampling converts to double.
enum class VoxelType : uint8_t { kUint8, kInt16, kUint16, kInt32, kFloat32, kFloat64 };

// Bytes per voxel of `type`.
size_t VoxelSize(VoxelType type);

// Lower-case name ("int16", "float32", ...), as used in messages and files.
std::string_view VoxelTypeName(VoxelType type);

// Inverse of VoxelTypeName; nullopt for an unknown name.
std::optional<VoxelType> VoxelTypeFromName(std::string_view name);

}  // namespace tetrefine
