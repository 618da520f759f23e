#pragma once

// Internal to the refine passes (core/refine.cc, edge_marking.cc, subdivide.cc): the state
// carried from one iteration to the next and the helpers every pass shares. Not a public API.

#include <atomic>
#include <cstdint>
#include <functional>
#include <vector>

#include "core/mesh.h"
#include "core/volume.h"

namespace tetrefine::refine_internal {

// The refinement state. Until the first subdivision the points and tets are the caller's, not
// a copy (a copy of a large mesh is a serial step that showed in the 2-thread profile);
// `points` and `tets` say where they are.
struct State {
  Mesh mesh;  // values always; points and tets once a subdivision has made them
  const std::vector<Vec3>* points = nullptr;
  const std::vector<Tet>* tets = nullptr;
  std::vector<int32_t> tet_iteration;  // T: iteration that created each tet (0 = input)
  std::vector<float> tet_quality;      // T: mean-ratio quality
  std::vector<int32_t> tet_label;      // T region labels, or empty when the input has none
  std::vector<uint32_t> tet_parent;    // T input tet of each tet, or empty when not tracked
  // Certified mode: T lattice discrepancies, or -1 for a tet not sampled yet. A tet keeps its
  // vertices and their values until it is split, so a tet is sampled once in its life; a tet
  // above epsilon is split in the same iteration.
  std::vector<double> tet_lattice_error;
  // Certified mode: T sums of each sampled tet's lattice discrepancies (CheckLatticeUntil's
  // sum_error, for the final verification), NaN where the tet was not sampled yet or failed.
  std::vector<double> tet_lattice_sum;

  // Points `points` and `tets` at the state's own mesh (after it was made or moved).
  void UseOwnMesh() {
    points = &mesh.points;
    tets = &mesh.tets;
  }
};

// Cancellation polled from worker threads; once seen it stays set.
class CancelFlag {
 public:
  explicit CancelFlag(const std::function<bool()>& poll) : poll_(poll) {}
  bool Check() {
    if (set_.load(std::memory_order_relaxed)) return true;
    if (poll_ && poll_()) set_.store(true, std::memory_order_relaxed);
    return set_.load(std::memory_order_relaxed);
  }
  bool IsSet() const { return set_.load(std::memory_order_relaxed); }

 private:
  const std::function<bool()>& poll_;
  std::atomic<bool> set_{false};
};

inline Vec3 Midpoint(const Vec3& a, const Vec3& b) {
  return {0.5 * (a[0] + b[0]), 0.5 * (a[1] + b[1]), 0.5 * (a[2] + b[2])};
}

// Trilinear value at a point inside the mesh's hull (a midpoint or a Steiner point).
inline double SampleInside(const Volume& volume, const Vec3& p, bool clamp) {
  Vec3 u = volume.ContinuousIndex(p);
  if (clamp) u = volume.ClampToGrid(u);
  return volume.SampleIndex(u);
}

inline double SquaredDistance(const Vec3& a, const Vec3& b) {
  const double dx = a[0] - b[0], dy = a[1] - b[1], dz = a[2] - b[2];
  return dx * dx + dy * dy + dz * dz;
}

}  // namespace tetrefine::refine_internal
