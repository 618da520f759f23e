#pragma once

// The closure and guard passes of one longest-edge iteration, run to the same marks with far
// fewer tet visits. Internal to Refine.

#include <cstdint>
#include <vector>

#include "core/edge_marking.h"

namespace tetrefine::refine_internal {

// How the closure and the guard follow each other in an iteration (SchemeRules, core/refine.cc).
struct MarkingRules {
  int closure_rounds = 0;  // CloseToLongestEdges' rounds per call; 0: no closure
  double guard_ratio = 0.0;
  double guard_floor = 0.0;  // absolute mean ratio (PromoteBadSplits); 0: none
  int guard_rounds = 0;      // guard passes, each followed by a closure call
  bool best_tiling = false;
  // After the last closure, one FinalGuardPass (core/edge_marking.h) with the guard's ratio and
  // floor; needs best_tiling and guard_rounds > 0.
  bool final_guard = false;
};

struct MarkingCounts {
  int64_t closure_edges = 0;  // edges the closure calls added
  int64_t guard_edges = 0;    // edges the guard passes added
};

// Exactly the marks and counts of
//   CloseToLongestEdges(closure_rounds);
//   guard_rounds times: PromoteBadSplits(guard_ratio, guard_floor, best_tiling);
//                       CloseToLongestEdges(...)
//   with final_guard: FinalGuardPass(guard_ratio, guard_floor)
// (a closure call only when closure_rounds > 0), on `split` (E entries), given edges.tet_edges.
// The last pass's edges count as the guard's.
//
// Both rules read a tet's split pattern and its corners only, and marks are only ever added, so
// a tet whose pattern has not changed since a rule last visited it adds nothing new. After a
// rule's first full pass, each pass therefore visits only the tets around the edges marked since
// that rule's previous pass (an edge-to-tet index, built once per iteration when first needed).
// Measured 2026-11-25 on the file-to-file case (bench/file_to_file.sh: 605 k tets, 22 closure
// rounds and 2 guard passes in its second iteration, identical output): those passes took
// 0.60 s of a 1.0 s iteration on two threads, visiting 605 k tets each.
//
// `tilings` (optional): with best_tiling and a guard, filled with T entries, the tiling key
// BestTiling gave each tet at the guard's last look at it, kUnknownTiling for the others; the
// subdivision reuses them (StepLimits::known_tilings) instead of choosing again.
//
// Polls `cancel` per block; once it is set the marks are incomplete and the caller must stop.
MarkingCounts CloseAndGuard(const std::vector<Vec3>& points, const std::vector<Tet>& tets,
                            const EdgeTable& edges, const MarkingRules& rules,
                            FillLater<uint8_t>& split, CancelFlag& cancel,
                            FillLater<uint16_t>* tilings = nullptr);

}  // namespace tetrefine::refine_internal
