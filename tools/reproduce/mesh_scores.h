#pragma once

#include <cstdint>

#include "core/mesh.h"
#include "core/quality.h"
#include "core/volume.h"

namespace tetrefine::reproduce {

// Mean-ratio quality (core MeanRatio) over every tet of `mesh`: min, mean and count.
QualityStats MeshQuality(const Mesh& mesh);

// Eq. 3 at the midpoint of every unique edge of `mesh`: |trilinear(midpoint) - (v_a + v_b) / 2|
// / norm_coeff, as core's EvaluateEdges computes it (the volume sampled with the grid clamp).
// `mesh.values` must hold one value per point. This is what a method's next round would mark.
struct MidpointErrorStats {
  int64_t edges = 0;
  double max_error = 0.0;
  double mean_error = 0.0;  // over unique edges
};
MidpointErrorStats MidpointErrors(const Volume& volume, const Mesh& mesh, double norm_coeff);

}  // namespace tetrefine::reproduce
