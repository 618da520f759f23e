#pragma once

#include <cstdint>

#include "core/mesh.h"
#include "core/volume.h"

namespace tetrefine {

// The edge-midpoint discrepancy (eq. 3) over a mesh's unique edges, as Refine reports it: an
// iteration's IterationStats::max_error and mean_error are these of the mesh it starts from, and
// RefineResult::final_max_error and final_mean_error these of the output, to the bit (the same
// edge order, samples and sums). For callers that hold a whole mesh Refine did not measure in one
// call: the sharded client's merged mesh, whose parts each measure their own edges, halos and
// part boundaries included.
struct EdgeMidpointStats {
  int64_t edges = 0;        // unique edges
  double max_error = 0.0;   // largest discrepancy
  double mean_error = 0.0;  // mean over the unique edges; 0 without edges
};

// mesh: valid tets (indices in range) with `values`, one per point (Refine's: the volume sampled
// there). norm: eq. 3's normCoeff, > 0. clamp: OutsidePolicy::kClamp's sampling (points clamped
// into the grid). Parallel over vertex blocks; the result does not depend on the thread count.
EdgeMidpointStats MeasureEdgeMidpoints(const Volume& volume, const Mesh& mesh, double norm,
                                       bool clamp);

}  // namespace tetrefine
