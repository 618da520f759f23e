#pragma once

#include "core/volume.h"

namespace tetrefine {

// The largest discrepancy of eq. 3, unnormalised, along a whole segment:
//   max over t in [0, 1] of |trilinear(a + t (b - a)) - ((1 - t) value_a + t value_b)|
// where trilinear is the volume's field (paper eq. 1) and value_a, value_b the values the mesh
// holds at a and b (world points, both in the volume's sampled box; with `clamp` their indices
// are clamped into the grid first, as refinement samples them).
//
// Why exact rather than sampled: along a segment the trilinear field is a cubic polynomial in t
// between the points where the segment crosses a voxel-cell face, so the maximum of the
// difference lies at a crossing or at a root of the cubic's derivative, and both are found in
// closed form. A long edge can pass the paper's midpoint test while the field departs from
// linear along it by a third of the range (measured on the bundled MRI volumes); the midpoint
// test then keeps splitting the short edges around it, which is what flattened the paper
// scheme's tets.
//
// The result depends only on the segment, not on which end is `a`: the ends are put in
// lexicographic order of their coordinates first, so two shards (or two numberings) that see
// the same edge compute the same bits.
double MaxSegmentDiscrepancy(const Volume& volume, const Vec3& a, const Vec3& b, double value_a,
                             double value_b, bool clamp);

}  // namespace tetrefine
