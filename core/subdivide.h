#pragma once

// One subdivision step: every tet is replaced by the children the 64-case table gives for its
// split edges (core/subdivision_table.h). Internal to Refine.

#include <cstdint>

#include "core/edge_marking.h"
#include "core/edge_table.h"
#include "core/fill_later.h"
#include "core/refine.h"
#include "core/refine_state.h"
#include "core/volume.h"

namespace tetrefine::refine_internal {

enum class StepOutcome { kApplied, kCancelled, kTetBudget, kQualityFloor };

struct StepLimits {
  int64_t max_tets = 0;      // refuse a step that would make more tets
  double min_quality = 0.0;  // refuse a step that would make a tet of lower quality
  bool clamp = false;        // Steiner points sampled clamped into the grid
  bool best_tiling = false;  // each tet cut by BestTiling (core/alternative_tilings.h)
  // Optional with best_tiling, T entries: a tiling key BestTiling already gave tet t, or
  // kUnknownTiling (CloseAndGuard's `tilings`). Used when its subdivision key is the tet's.
  const FillLater<uint16_t>* known_tilings = nullptr;
};

// Subdivides every tet of `state` whose edges are split (errors.split, errors.mid_value) with
// edges.tet_edges filled. Leaves `state` alone unless it returns kApplied; for kTetBudget
// *next_tets says how many tets it needed, for kQualityFloor *next_quality its worst tet.
// Children inherit their parent's label and input tet; new tets are not certified.
// Output order: old vertices keep their ids, then midpoints in edge order, then Steiner points
// in tet order; children in parent order.
// `succession` (optional) is filled when it returns kApplied: where each old tet's children went
// (UpdateTetEdges reads it).
StepOutcome Subdivide(const Volume& volume, const EdgeTable& edges, const EdgeErrors& errors,
                      int iteration, const StepLimits& limits, CancelFlag& cancel, State& state,
                      IterationStats& stats, int64_t* next_tets, double* next_quality,
                      TetSuccession* succession = nullptr);

}  // namespace tetrefine::refine_internal
