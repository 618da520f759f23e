#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "core/mesh.h"
#include "core/volume.h"

namespace tetrefine::reproduce {

// The paper's section 5.1: where in a tet does the largest discrepancy between trilinear and
// linear interpolation lie, on the 165-point lattice (n = 8)?
//
// What is counted, per tet (of all tets, or of a seeded random sample of max_tets of them):
// the lattice point of largest error, found by core's SampleTetLattice (ties: the first point in
// its i, j, k order), classified by core's MaxLocation (vertex, edge midpoint, other edge point,
// face, interior). A tet counts towards a threshold when that largest error exceeds it (relative
// to norm_coeff): tets that agree everywhere have no meaningful maximum. "Near an edge midpoint"
// (the paper's "at the midpoint of some edge or in a point near to this one") adds the lattice
// points one step from an edge midpoint: (i, j, k, l) with two coordinates n/2 +- 1 or one moved
// onto a third coordinate, i.e. within barycentric L1 distance 2/n of a midpoint.
inline constexpr int kNumMaxLocations = 5;  // core's MaxLocation enumerators

struct LocationCounts {
  double threshold = 0.0;
  int64_t counted = 0;                                  // tets whose max error > threshold
  std::array<int64_t, kNumMaxLocations> by_location{};  // indexed by MaxLocation
  int64_t near_midpoint = 0;                            // edge midpoint or one lattice step away
};

struct LocationStudy {
  int64_t tets = 0;                    // in the mesh
  int64_t tets_sampled = 0;            // examined
  std::vector<LocationCounts> counts;  // one per threshold
  // Tets where this study's own scan found a different argmax class than core: 0 unless the two
  // disagree on ties (a sanity check on the "near" classification, which needs the point).
  int64_t class_mismatches = 0;
};

// `mesh` without values gets them sampled from `volume`. Runs on all cores.
LocationStudy StudyMaxLocation(const Volume& volume, Mesh mesh, double norm_coeff,
                               const std::vector<double>& thresholds, int64_t max_tets,
                               uint64_t seed);

}  // namespace tetrefine::reproduce
