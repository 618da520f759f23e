#pragma once

#include <array>
#include <span>
#include <string>
#include <vector>

#include "core/volume.h"

namespace tetrefine {

// Checks that `tets` (indices into `points`) tile the region bounded by the triangles `boundary`:
// every tet has positive volume, every boundary triangle is the face of exactly one tet, every
// other face is shared by exactly two tets lying on opposite sides of it, and no face is shared
// by more. By a degree argument this means the tets cover the region exactly once. On failure
// returns false and says why in *why (when not null).
bool IsTiling(std::span<const std::array<int, 4>> tets,
              std::span<const std::array<int, 3>> boundary, std::span<const Vec3> points,
              std::string* why);

}  // namespace tetrefine
