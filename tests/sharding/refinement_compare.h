#pragma once

// Comparing a sharded refinement with the unsharded one, independent of numbering.

#include "core/mesh.h"
#include "core/refine.h"

namespace tetrefine::testing {

// Expects the same refinement to the bit: the same vertices (position and value) and the same
// tets (corner positions in order, iteration, quality) after sorting both; input vertices at
// their input indices; no duplicated vertex; and the statistics that sharding keeps exact (tet
// counts and configurations per iteration, maxima, minima, stop reason, norm_coeff), and the
// final edge-midpoint mean, which the client measures on the merged mesh (to its sum's rounding:
// the merged mesh is numbered part by part, so its edges are summed in another order).
// whole_mesh_statistics: the run went one iteration at a time with halos (the longest-edge
// scheme, certify), whose client measures the merged mesh after every iteration: edge counts,
// other tilings and the iterations' edge-midpoint means are the unsharded run's too.
void ExpectSameRefinement(const Mesh& input, const RefineResult& unsharded,
                          const RefineResult& sharded, bool whole_mesh_statistics = false);

// Whether the two results have the same tets (as ExpectSameRefinement compares them), for
// tests that need a refinement to differ.
bool SameTets(const RefineResult& a, const RefineResult& b);

}  // namespace tetrefine::testing
