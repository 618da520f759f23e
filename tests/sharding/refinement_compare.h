#pragma once

// Comparing a sharded refinement with the unsharded one, independent of numbering.

#include "core/mesh.h"
#include "core/refine.h"

namespace tetrefine::testing {

// Expects the same refinement to the bit: the same vertices (position and value) and the same
// tets (corner positions in order, iteration, quality) after sorting both; input vertices at
// their input indices; no duplicated vertex; and the statistics that sharding keeps exact (tet
// counts and configurations per iteration, maxima, minima, stop reason, norm_coeff).
void ExpectSameRefinement(const Mesh& input, const RefineResult& unsharded,
                          const RefineResult& sharded);

// Whether the two results have the same tets (as ExpectSameRefinement compares them), for
// tests that need a refinement to differ.
bool SameTets(const RefineResult& a, const RefineResult& b);

}  // namespace tetrefine::testing
