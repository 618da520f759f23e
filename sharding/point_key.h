#pragma once

// Exact-bit identity of points and values, by which refined parts are stitched back together: a
// vertex several parts create (an edge midpoint) is computed from the same endpoints in each, so
// it has the same bits everywhere.

#include <array>
#include <bit>
#include <cstdint>

#include "core/mesh.h"

namespace tetrefine::sharding {

// A part's vertex not yet given an index in the stitched-together whole.
inline constexpr uint32_t kUnsetIndex = UINT32_MAX;

using PointKey = std::array<uint64_t, 3>;  // the bits of x, y, z

inline PointKey KeyOf(const Vec3& p) {
  return {std::bit_cast<uint64_t>(p[0]), std::bit_cast<uint64_t>(p[1]),
          std::bit_cast<uint64_t>(p[2])};
}

inline bool SameBits(double a, double b) {
  return std::bit_cast<uint64_t>(a) == std::bit_cast<uint64_t>(b);
}

}  // namespace tetrefine::sharding
