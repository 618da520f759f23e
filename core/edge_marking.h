#pragma once

// Which edges an iteration splits: the edge test of the scheme (core/refine.h), then the
// longest-edge closure of the conforming schemes and, in certified mode, the tets whose lattice
// fails. Internal to Refine.

#include <array>
#include <cstdint>
#include <vector>

#include "absl/functional/function_ref.h"
#include "core/alternative_tilings.h"
#include "core/edge_table.h"
#include "core/fill_later.h"
#include "core/refine_state.h"
#include "core/tets_around.h"
#include "core/volume.h"

namespace tetrefine::refine_internal {

// How an edge is judged.
enum class EdgeTest : uint8_t {
  kMidpoint,  // the paper's eq. 3 at the edge midpoint only
  kSegment,   // the exact maximum of eq. 3 along the whole edge (core/segment_error.h)
};

struct EdgeTestParams {
  EdgeTest test = EdgeTest::kMidpoint;
  double norm = 1.0;             // normCoeff of eq. 3
  double epsilon = 0.1;          // an edge whose error exceeds this fails
  double min_edge_length = 0.0;  // failing edges shorter than this are kept whole
  bool clamp = false;            // sample points clamped into the grid
};

// Per unique edge (EdgeTable order): the trilinear value at its midpoint (the value a new vertex
// there gets) and whether the iteration splits it. Statistics are over unique edges.
struct EdgeErrors {
  FillLater<double> mid_value;      // E
  FillLater<double> segment_error;  // E, normalised; kSegment only (empty for kMidpoint)
  FillLater<uint8_t> split;         // E: 1 when split
  int64_t failing = 0;              // edges whose test failed (and were long enough to split)
  int64_t short_kept = 0;           // failing edges kept whole: shorter than min_edge_length
  double max_error = 0.0;           // max midpoint error (the paper's statistic, whatever the test)
  double mean_error = 0.0;
  double max_segment_error = 0.0;  // kSegment: max along edges; else 0
};

// The previous iteration's edges and what was computed for them. Subdivision keeps the old
// vertices' ids and values, and joins two old vertices only along an old edge it did not split
// (a child's corners are its parent's corners, edge midpoints and Steiner point), so every edge
// of the refined mesh between two old vertices is in this table with the same midpoint value
// and segment error. The next evaluation reads those instead of sampling the volume again: the
// same bits, and most of a late iteration's edges are such edges.
struct KnownEdges {
  EdgeTable edges;           // without tet_edges
  FillLater<uint8_t> split;  // the marks the subdivision applied (UpdateEdgeTable)
  FillLater<double> mid_value;
  FillLater<double> segment_error;  // empty unless the test was kSegment
};

// Judges every unique edge of the state's mesh. `known` may be null.
EdgeErrors EvaluateEdges(const Volume& volume, const State& state, const EdgeTable& edges,
                         const EdgeTestParams& params, const KnownEdges* known, CancelFlag& cancel);

// Local index (kTetEdges) of the longest edge of the tet with corners p. Equal lengths are broken
// by geometry (the edge whose lexicographically smaller endpoint, then larger endpoint, is
// smallest), never by numbering, so every tet sharing the edge agrees and shards agree.
int LongestEdge(const std::array<Vec3, 4>& p);

// The edges the closure and the guard's remedies read for a tet with corners p, as local indices
// (kTetEdges), 3 bits each: bits 0-2 its longest edge (LongestEdge(p)), bits 3 + 3f .. 5 + 3f the
// longest edge of face f (kTetFaces order). Equal lengths are broken as LongestEdge breaks them, by
// geometry, so the two tets of a face agree on its longest edge.
uint32_t ClosureTargets(const std::array<Vec3, 4>& p);

// Longest-edge closure, `rounds` times: every face with a split edge also splits its longest
// edge (Plaza's rule; until 2026-11-28 every tet with a split edge its longest edge too: see
// SchemeRules in core/refine.cc). Each round reads the marks of the round before (never marks made
// in the same round), so the result does not depend on the order tets are visited in. Needs
// edges.tet_edges. Returns the number of edges the closure added. Polls `cancel` per block: once
// it is set the marks are incomplete and the caller must stop.
//
// `targets` (T entries, or null): a cache of each tet's ClosureTargets, kTargetsUnknown where not
// yet computed, shared by the closure calls of one iteration. The closure passes of an iteration
// (up to 24 in the longest-edge scheme) meet the same tets again and again; LongestEdge alone was
// 6.6% of a whole call when each pass recomputed it (bench/core_bench BM_ToConvergence,
// 2026-11-24).
inline constexpr uint16_t kTargetsUnknown = 0xffff;
int64_t CloseToLongestEdges(const std::vector<Vec3>& points, const std::vector<Tet>& tets,
                            const EdgeTable& edges, int rounds, FillLater<uint8_t>& split,
                            CancelFlag& cancel, FillLater<uint16_t>* targets = nullptr);

// One closure round (what CloseToLongestEdges does `rounds` times) over the tets in `visit` (each
// at most once; all tets when null), with the targets cache (T entries) required. Sets the marks
// after the pass, appends the edges it newly marked to `fresh` when not null, and returns their
// number. A round over a list marks what a round over all tets marks when every tet left out
// has the split pattern it had when a round last visited it (core/marking_sequence.h).
int64_t ClosureRound(const std::vector<Vec3>& points, const std::vector<Tet>& tets,
                     const EdgeTable& edges, FillLater<uint8_t>& split, CancelFlag& cancel,
                     FillLater<uint16_t>& targets, const std::vector<uint32_t>* visit,
                     std::vector<uint32_t>* fresh);

// What the quality guard gives a tet whose split would make a child below `threshold`
// (GuardPass). Regular 1:8 refinement (all six edges) was the guard's only remedy until
// 2026-11-27; it marks edges the split did not need, and each of them brings the tets around it
// into the closure. This remedy is the split pattern, a superset of `pattern` (a tet's split
// edges, EdgeBit of local edges; neither 0 nor 63), with the fewest edges added that
//   - is closed within the tet: it holds the tet's longest edge (as longest-edge bisection cuts
//     a tet), and the longest edge of every face it splits (ClosureTargets), so the closure adds
//     nothing to it from this tet, and
//   - has a best tiling (ChooseTiling) whose worst child is at or above `threshold`;
// all six when no smaller set does. Among sets of one size: the best worst child, then the
// longer added edges (the edges of each set sorted longest first, as LongestEdge orders them),
// so the choice depends on geometry only, never on numbering.
//
// Measured 2026-11-27 on the 40 longest-edge and certify runs of the reproduction
// (`tetrefine_reproduce --skip_peers`, docs/schemes.md "A guard that adds the fewest edges"):
// 1.9% fewer tets, the same stop reasons, and the same worst tet in every run.
struct GuardRemedy {
  uint32_t pattern = 63;             // the split pattern the guard gives the tet
  uint32_t tiling = kUnknownTiling;  // BestTiling of that pattern's key (not looked up for 63)
};
GuardRemedy FewestGuardEdges(uint32_t pattern, const std::array<Vec3, 4>& corners,
                             double threshold);

// One round of the quality guard: every tet whose split (by the paper's table, or with
// best_tiling by its best tiling) would make a child of mean-ratio quality below
// max(`ratio` times its own, `floor`) gets more split edges: with best_tiling the fewest that
// make a split above that threshold (FewestGuardEdges), else all six (regular 1:8 refinement
// keeps at least 0.77 of the parent's quality, measured). `floor` is an absolute mean ratio, the
// same for every tet of a run (0: none). Returns edges added.
// Polls `cancel` as CloseToLongestEdges does.
int64_t PromoteBadSplits(const std::vector<Vec3>& points, const std::vector<Tet>& tets,
                         const EdgeTable& edges, double ratio, double floor, bool best_tiling,
                         FillLater<uint8_t>& split, CancelFlag& cancel);

// PromoteBadSplits over the tets in `visit` (all when null), as ClosureRound is to a closure
// round: the same conditions for a list, and the same `fresh` edges. With best_tiling and
// `tilings` (T entries) not null, each tet the guard judges gets the tiling key BestTiling gave
// it there: for its key, or for a tet given more edges the key of its remedy (Subdivide reuses
// it while the tet's subdivision key is that key).
int64_t GuardPass(const std::vector<Vec3>& points, const std::vector<Tet>& tets,
                  const EdgeTable& edges, double ratio, double floor, bool best_tiling,
                  FillLater<uint8_t>& split, CancelFlag& cancel, const std::vector<uint32_t>* visit,
                  std::vector<uint32_t>* fresh, FillLater<uint16_t>* tilings = nullptr);

// The guard's last look, after the iteration's last closure (MarkingRules::final_guard). The
// closure that follows each guard pass completes patterns no guard pass sees again: on the
// reproduction those were the worst tets of the runs below 0.5x of the input's worst tet. A
// plain guard pass there does not help, because its edges make new unguarded splits around the
// tets it fixes (docs/schemes.md, "A floor under the guard"). So this pass takes a remedy only
// if it spares the neighbours: for a tet whose split has a child below `threshold`, the fewest
// more split edges (any of its unsplit edges: no closure follows) such that
//   - its best tiling's worst child is at or above `threshold`, and
//   - spares(add) holds: the caller checks that no tet around the added edges (local edges
//     `add`, EdgeBit) gets a split below both its own threshold and its split before;
// among sets of one size the best worst child, then the longer added edges (as
// FewestGuardEdges), so the choice depends on geometry only. Returns the pattern with the
// remedy (a superset of `pattern`, maybe 63), or `pattern` itself when no set qualifies: the tet
// is then cut as its marks say.
GuardRemedy SparingGuardEdges(uint32_t pattern, const std::array<Vec3, 4>& corners,
                              double threshold, absl::FunctionRef<bool(uint32_t add)> spares);

// The worst child of the tet with corners `corners` cut by split pattern `pattern` (EdgeBit of
// local edges) in its best tiling: ChooseTiling's worst; for pattern 0 the tet's own quality.
double WorstChildOf(uint32_t pattern, const std::array<Vec3, 4>& corners);

// One pass of the guard's last look over the tets in `visit` (all when null): each tet whose
// split (by its best tiling) has a child below max(`ratio` times its own quality, `floor`) gets
// SparingGuardEdges' remedy, where a neighbour is spared when its new split's worst child is at
// or above its own threshold or at or above its split's before (`around` finds the tets of an
// edge). Every tet reads the marks as they were before the pass, so the result does not depend
// on the order of visits; two remedies applied together may still meet in a neighbour.
// `tilings` (T entries, or null) as GuardPass fills it. Returns the edges added; appends them to
// `fresh` when not null. Polls `cancel` as CloseToLongestEdges does.
int64_t FinalGuardPass(const std::vector<Vec3>& points, const std::vector<Tet>& tets,
                       const EdgeTable& edges, const TetsAround& around, double ratio, double floor,
                       FillLater<uint8_t>& split, CancelFlag& cancel,
                       const std::vector<uint32_t>* visit, std::vector<uint32_t>* fresh,
                       FillLater<uint16_t>* tilings = nullptr);

// Certified mode: samples every tet not sampled yet on the lattice of order n (the paper's 165
// points for n = 8) and keeps its discrepancy in state.tet_lattice_error (final until the tet is
// split), and for a tet that passes the sum of its errors in state.tet_lattice_sum (the final
// verification reads both, SampleLattice's `known`); a tet above epsilon gets its longest edge
// split, unless that edge is shorter than params.min_edge_length (then so are the others, and the
// tet is kept whole, counted in *kept: a sweep found --certify splitting such edges down to
// 0.04 mm under --min-edge-length 100). Returns the number of failing tets marked.
// Splitting instead the edge nearest the tet's lattice maximum (largest sum of the point's two
// barycentric weights, longest on ties) was measured 2026-11-24 on the unit cube fitted to the
// three real volumes at eps 0.1 and 0.05 (`refine --certify --fit-mesh-to-volume`): 7-12% more
// tets in every run and a worse worst tet in five of six (epi eps 0.1: 185,861 tets, min
// 0.146, against 165,485 and 0.172). The longest edge shrinks the tet fastest.
int64_t MarkFailingTets(const Volume& volume, State& state, const EdgeTable& edges, int n,
                        const EdgeTestParams& params, FillLater<uint8_t>& split, CancelFlag& cancel,
                        int64_t* kept);

}  // namespace tetrefine::refine_internal
