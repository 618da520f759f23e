#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "core/lattice.h"
#include "core/volume.h"

// The inner loop of the lattice verification (SampleLattice, and certified mode's check of every
// new tet each iteration): millions of trilinear samples per call. Internal to core.
namespace tetrefine::lattice_internal {

// The barycentric lattice (i, j, k, l) / n, i + j + k + l = n, in scan order (i, then j, then k
// ascending), with each coordinate stored as i * (1.0 / n): the bits SampleTetLattice has always
// used, computed once instead of per point.
class LatticePoints {
 public:
  // n >= 1. with_corners = false leaves out the 4 tet corners (certified mode: a corner is an
  // exact sample, its error is 0 by construction) and keeps the others in the same order.
  LatticePoints(int n, bool with_corners);

  int n() const { return n_; }
  // Number of points: (n + 1)(n + 2)(n + 3) / 6, less 4 without corners.
  int64_t size() const { return static_cast<int64_t>(location_.size()); }
  // Coordinate c (0..3, the weight of tet corner c) of every point, size() values.
  const double* b(int c) const { return b_[c].data(); }
  // Where point i lies in the tet (vertex, edge midpoint, edge, face, interior).
  MaxLocation location(int64_t i) const { return location_[i]; }

 private:
  int n_;
  std::array<std::vector<double>, 4> b_;
  std::vector<MaxLocation> location_;
};

// Whether LatticeErrors runs its AVX2 version (x86-64 CPUs that have AVX2; the same bits as the
// portable one). SetLatticeSimdForTesting switches it for tests of both paths; it returns false
// when the version asked for cannot run here.
bool LatticeSimd();
bool SetLatticeSimdForTesting(bool on);

// Volume::SampleIndex at the `count` continuous indices (ux[i], uy[i], uz[i]), into out[i]: the
// same bits, four at a time where the AVX2 kernel runs. For callers with many samples to take
// (the edge test's midpoints).
void SampleIndices(const Volume& volume, const double* ux, const double* uy, const double* uz,
                   int64_t count, double* out);

// Most points LatticeErrors takes per call: its scratch lives on the stack.
inline constexpr int64_t kLatticeChunk = 64;

// Discrepancy of eq. 3, |trilinear(volume) - linear(values)| / norm, at points [begin, end) of
// `points` (end - begin <= kLatticeChunk) in the tet with corners p and corner values v, into
// errors[0 .. end - begin). Bit for bit what SampleTetLattice always computed per point:
// x = ((0 + b0 p0 + b1 p1) + b2 p2) + b3 p3 per axis, likewise the linear value, then
// Volume::ContinuousIndex and Volume::SampleIndex. Clamping to the grid (OutsidePolicy::kClamp)
// needs no flag: SampleIndex clamps to the grid's box itself, and clamping twice is clamping once.
void LatticeErrors(const Volume& volume, const LatticePoints& points, const std::array<Vec3, 4>& p,
                   const std::array<double, 4>& v, double norm, int64_t begin, int64_t end,
                   double* errors);

// SampleTetLattice's statistics for one tet (corners p, values v) over `points` (which must
// include the corners), with the same strict comparisons and ties.
TetLattice ScanTetLattice(const Volume& volume, const LatticePoints& points,
                          const std::array<Vec3, 4>& p, const std::array<double, 4>& v, double norm,
                          double epsilon);

// Certified mode's test of one tet: the discrepancy over `points` scanned in order, stopping at
// the first point above epsilon (the caller only needs to know whether the tet fails). Points
// are evaluated a chunk at a time; the scan stops where a point-by-point one would.
struct LatticeCheck {
  bool passed = true;      // no point above epsilon
  double max_error = 0.0;  // the largest discrepancy up to where the scan stopped
  // For a tet that passed, over every point: ScanTetLattice's sum_error, to the bit (summed in
  // the same order from the same errors), so that a final verification over the same points
  // can take the tet's statistics from here (SampleLattice's `known`). Unspecified otherwise.
  double sum_error = 0.0;
};
LatticeCheck CheckLatticeUntil(const Volume& volume, const LatticePoints& points,
                               const std::array<Vec3, 4>& p, const std::array<double, 4>& v,
                               double norm, double epsilon);

}  // namespace tetrefine::lattice_internal
