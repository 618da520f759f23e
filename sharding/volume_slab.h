#pragma once

// The part of a volume a mesh part needs.

#include <vector>

#include "absl/status/statusor.h"
#include "core/mesh.h"
#include "core/volume.h"

namespace tetrefine::sharding {

struct SlabBox {
  Index3 lo{0, 0, 0};  // first sample per axis
  Index3 hi{0, 0, 0};  // one past the last
};

// The samples of `volume` (a whole volume or a slab) that refining a mesh with vertices `points`
// reads: the cells holding the points' bounding box plus one voxel on each side, clamped to the
// samples `volume` has. Refinement never leaves the convex hull of the input, and Volume samples
// a point with the same bits from any slab holding its cell, so values sampled from this slab
// equal those sampled from `volume`. The margin covers points on a cell face, where either
// neighbouring cell may be chosen. `clamp_to_grid`: points are clamped into the grid's box first,
// as OutsidePolicy::kClamp does. Every point must be finite.
SlabBox SlabCovering(const Volume& volume, const std::vector<Vec3>& points, bool clamp_to_grid);

// A copy of the samples of `volume` in `box` (which must lie within volume.lo()/hi()).
absl::StatusOr<Volume> CutSlab(const Volume& volume, const SlabBox& box);

}  // namespace tetrefine::sharding
