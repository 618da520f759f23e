#pragma once

#include "core/mesh.h"
#include "core/volume.h"

namespace tetrefine::reproduce {

// The baseline the paper's scheme is measured against: regular 1:8 refinement of every tet
// (every edge split at its midpoint, the central octahedron cut along its shortest diagonal:
// core's subdivision table entry for pattern 63), ignoring the data. Midpoints are shared by
// edge, so the result is conformal; a new vertex gets the volume's trilinear value there, as in
// the paper. `mesh` must carry values; points must lie in the volume's box.
Mesh UniformRefine(const Volume& volume, const Mesh& mesh);

// Values of `mesh`'s points sampled from `volume` (what Refine assigns to input vertices).
void SampleValues(const Volume& volume, Mesh& mesh);

}  // namespace tetrefine::reproduce
