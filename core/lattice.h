#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <vector>

#include "core/mesh.h"
#include "core/refine.h"
#include "core/volume.h"

namespace tetrefine {

// Where in a tet the largest lattice discrepancy lies (paper section 5.1).
enum class MaxLocation : uint8_t { kVertex, kEdgeMidpoint, kEdge, kFace, kInterior };

// Where the lattice point (i, j, k, l) / n (ijkl, i + j + k + l = n) lies in its tet.
MaxLocation LatticeLocation(int n, const std::array<int, 4>& ijkl);

// Discrepancy of eq. 3 at the barycentric lattice points (i, j, k, l) / n, i + j + k + l = n,
// of tet t of `mesh` (values per vertex): realValue by trilinear sampling of `volume` (clamped
// to the grid when clamp is set), aproxValue by linear interpolation.
struct TetLattice {
  double max_error = 0.0;
  double sum_error = 0.0;
  int64_t points = 0;
  int64_t above_epsilon = 0;
  MaxLocation max_location = MaxLocation::kVertex;
};
TetLattice SampleTetLattice(const Volume& volume, const Mesh& mesh, int64_t t, int n,
                            double norm_coeff, double epsilon, bool clamp);

// What a caller already measured of some tets' lattices (certified mode samples every tet of its
// result as the tet is made): per tet of the mesh, sum_error is NaN for a tet to sample, else the
// tet had no point above epsilon and max_error and sum_error are what SampleTetLattice would give
// for it with the same n, norm_coeff and epsilon (lattice_internal::CheckLatticeUntil's, to the
// bit). Both vectors hold one entry per tet, or are null.
struct KnownTetLattices {
  const std::vector<double>* max_error = nullptr;
  const std::vector<double>* sum_error = nullptr;
};

// The lattice statistics over all tets, or over max_tets tets drawn with `seed` when the mesh
// has more. Deterministic for a given seed whatever the thread count.
// `should_stop`, when set, is polled from worker threads every few thousand samples: at order 64
// over millions of tets the lattice alone runs for minutes, and a cancelled refinement must not.
// Once it returns true the remaining tets are skipped and the statistics are incomplete.
// `known` tets are not sampled again; the statistics are the same bits as without it.
LatticeStats SampleLattice(const Volume& volume, const Mesh& mesh, int n, int64_t max_tets,
                           uint64_t seed, double norm_coeff, double epsilon, bool clamp,
                           const std::function<bool()>& should_stop = {},
                           const KnownTetLattices& known = {});

}  // namespace tetrefine
