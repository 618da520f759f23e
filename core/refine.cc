#include "core/refine.h"

#include <tbb/info.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <limits>
#include <optional>
#include <string_view>

#include "absl/strings/str_cat.h"
#include "core/edge_marking.h"
#include "core/edge_table.h"
#include "core/lattice.h"
#include "core/marking_sequence.h"
#include "core/mesh_validation.h"
#include "core/parallel.h"
#include "core/refine_state.h"
#include "core/subdivide.h"

namespace tetrefine {
namespace {

using refine_internal::CancelFlag;
using refine_internal::EdgeErrors;
using refine_internal::EdgeTest;
using refine_internal::EdgeTestParams;
using refine_internal::KnownEdges;
using refine_internal::State;
using refine_internal::StepLimits;
using refine_internal::StepOutcome;

using Clock = std::chrono::steady_clock;

double SecondsSince(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

QualityStats SummarizeQuality(const std::vector<float>& q) {
  const int64_t n = static_cast<int64_t>(q.size());
  const int64_t blocks = BlockCount(n);
  std::vector<double> sums(blocks), mins(blocks);
  ForEachBlock(n, [&](int64_t b, int64_t begin, int64_t end) {
    double s = 0.0, m = 1.0;
    for (int64_t i = begin; i < end; ++i) {
      s += q[i];
      m = std::min(m, static_cast<double>(q[i]));
    }
    sums[b] = s;
    mins[b] = m;
  });
  QualityStats out;
  out.count = n;
  out.min = n > 0 ? 1.0 : 0.0;
  double sum = 0.0;
  for (int64_t b = 0; b < blocks; ++b) {
    sum += sums[b];
    out.min = std::min(out.min, mins[b]);
  }
  out.mean = n > 0 ? sum / static_cast<double>(n) : 0.0;
  return out;
}

// quality[t] = the mean ratio of tets[t] as a float, for t in [begin, end).
void TetQualities(const std::vector<Vec3>& p, const std::vector<Tet>& tets, int64_t begin,
                  int64_t end, float* quality) {
  constexpr int64_t kChunk = 256;  // MeanRatiosAsFloat's loop, on parts that stay in L1
  std::array<MeanRatioParts, kChunk> parts;
  for (int64_t first = begin; first < end; first += kChunk) {
    const int64_t n = std::min(kChunk, end - first);
    for (int64_t i = 0; i < n; ++i) {
      const Tet& t = tets[first + i];
      parts[i] = MeanRatioPartsOf(p[t[0]], p[t[1]], p[t[2]], p[t[3]]);
    }
    MeanRatiosAsFloat(parts.data(), n, quality + first);
  }
}

// What a scheme does, spelled out.
//
// The longest-edge scheme, and why (measured with the reproduction's cases, exp. notes in
// docs/schemes.md; "quality" is mean ratio, min and mean as output / input):
//  - The paper's scheme stops at the quality floor on most real cases: near a feature sharper
//    than the mesh it splits short edges inside tets whose long edges pass the midpoint test,
//    and the tets flatten (anatomical cube, eps 0.1: quality min 2e-6 after 14 iterations).
//  - Deciding edges by the exact maximum along them (EdgeTest::kSegment) alone does not fix it
//    (same case: quality_floor after 29 iterations, min 0.000, mean 0.53x).
//  - Longest-edge closure (a tet with a split edge also splits its longest edge, Rivara) makes
//    every case converge (10 of 10, eps 0.1 and 0.05, within 11 iterations) but keeps only
//    0.80-0.99x of the mean quality and 0.04-0.47x of the min: some of the table's
//    configurations lose quality fast (children / parent on random tets: 2b, 3c, 4a, 4b keep
//    0.77-0.82 on average and 0.38-0.49 at worst; regular 1:8 refinement, configuration 6,
//    keeps 0.99 and 0.77). Closure to a fixpoint helps little (min 0.31-0.57x) and is not
//    bounded in radius; replacing the table by longest-marked-edge bisection (Plaza-like)
//    did not help either (mean 0.80-0.88x: bisection's 8-way split keeps 0.85, red 0.99).
//  - A quality guard that acts on the tets concerned: a tet whose split would make a child below
//    kGuardRatio of its own quality splits all six edges instead (regular refinement; since
//    2026-11-27 the fewest edges that avoid it, below); two
//    rounds, each followed by the closure. With ratio 0.65 mean quality stays at 0.85-0.98x;
//    0.75 keeps 0.92-1.0x but doubles to quadruples the tets; 0.5 barely acts.
//  - The midpoint test with closure and guard converges as reliably as the exact segment test
//    and needs 10-30% fewer tets (anatomical cube eps 0.1: 31,031 against 43,613), so the
//    default keeps the paper's midpoint test; certified mode, which promises a bound, uses
//    the exact segment test for edges and the lattice for tets. Certify with the midpoint test
//    for edges (the lattice still catches the rest) was measured 2026-11-24 on the unit cube
//    fitted to the three real volumes at eps 0.1 and 0.05 (`refine --certify
//    --fit-mesh-to-volume`): 0.5-5% fewer tets in the four converging runs, worst tet better in
//    one and worse in three (anatomical eps 0.05: min 0.186 against 0.215): kept as is.
//    Measured again 2026-11-29 with the midpoint test only on edges at most 1-6 voxels long
//    (index units; docs/schemes.md "Certified mode: the segment test on long edges only"): at
//    2 voxels 2.2% fewer tets over the 18 converging reproduction runs and 7% over the 22
//    unseen ones, but on an anisotropic volume (0.3 x 0.3 x 5 mm voxels) 5.2x the tets at 1 and
//    2 voxels (360,203 -> 1,871,533: the lattice then finds what the edges missed, and splits
//    only a failing tet's longest edge), and one unseen run's worst tet 0.48x -> 0.26x of the
//    input's. Not adopted: a few percent do not pay for 5x on thick-slice volumes.
//  - Four closure rounds rather than two: fewer tets and a better worst tet (anatomical cube
//    eps 0.1: 28,731 tets, min 0.65x, against 31,031 and 0.59x; sharp blob of
//    tests/core/refine_test.cc: min 0.40x against 0.28x); more guard rounds cost tets for little.
//  - The closure also splits the longest edge of every face with a split edge (Plaza's rule,
//    which DOLFINx's refinement applies to a fixpoint), not only of every tet, with eight
//    rounds and guard ratio 0.6 instead of four and 0.65 (2026-11-24, all 20 reproduction runs,
//    docs/schemes.md "Face closure"): 19 runs converge instead of 18 (the T1 cube at eps 0.1
//    now does), the worst tet keeps 0.37-0.73x of the input's min instead of 0.27-0.65x (7 runs
//    below 0.5x instead of 13) for 1% more tets over the 18 runs both converge on; the mean
//    keeps 0.86-0.98x (6 runs below 0.9x instead of 5). With faces, guard 0.65 costs 15% more
//    tets and no guard misses 0.5x in 16 runs; four rounds leave a worst tet of 0.27x, sixteen
//    rounds change nothing more than eight. Certified mode gains the same quality (7 runs below
//    0.5x instead of 16) for 1% more tets, and keeps the same rules. On six meshes outside the
//    reproduction three come out better in tets and quality, two T1 block meshes take 17-32%
//    more tets for an equal or better worst tet, and the anatomical volume's 2-voxel block mesh
//    takes 2.7x the tets (the guard's 1:8 promotions cascade on its regular cells).
//    BM_ToConvergence: about the same time for 6% fewer tets.
//  - Each tet is cut by the best of the tilings its faces allow (core/alternative_tilings.h:
//    the table's, or another Steiner-free tiling of the same boundary, which 3c, 4a, 4b, 5 and
//    6 admit for some keys; the largest worst child wins), and the guard judges that tiling
//    (2026-11-25, all 20 reproduction runs, docs/schemes.md "Better tilings"): 2.6% fewer tets
//    in all, the mean quality higher in every run (runs below 0.9x: 6 -> 4), the min higher or
//    equal in every run (below 0.5x: 7 -> 6), the same runs converge. The two heart shells at
//    eps 0.05 take 32% and 17% more tets: their second iteration leaves more edges just above
//    eps. Certified: 2.5% fewer tets, runs below 0.9x mean 5 -> 4, two runs' min lower. With
//    it, guard ratio 0.65 costs 8% more tets and 0.55 leaves as many runs below 0.5x. On six
//    meshes outside the reproduction: tets -4% to +2%, min and mean equal or better in all
//    (anatomical 2-voxel blocks: min 0.218 -> 0.336).
//  - The guard gives a flagged tet the fewest more edges that make a split it accepts, closed
//    within the tet, instead of all six (FewestGuardEdges, core/edge_marking.h; all six only when
//    no smaller set does). Each needless edge of a 1:8 promotion brought the tets around it into
//    the closure. 2026-11-27, all 20 reproduction runs (docs/schemes.md "A guard that adds the
//    fewest edges"): 1.9% fewer tets (6,242,126 -> 6,126,072; certify 7,073,191 -> 6,940,064),
//    the same stop reasons and the same worst tet in all 40 runs, the mean at most 0.008 lower
//    (the same runs below 0.9x). With it, guard ratio 0.65 costs 3.4% more tets and 0.55 puts
//    one more run below 0.5x: 0.6 stays.
//  - The guard also keeps every child at kGuardFloor of the input's worst tet where it can
//    (RefineOptions::quality_reference): the threshold is max(0.6 x own, 0.5 x reference). The
//    guard's relative rule lets quality compound down over iterations (0.6 x 0.6 = 0.36); a floor
//    measured 2026-11-23 with regular 1:8 refinement as the only remedy made things worse (1:8
//    cannot keep 0.5 below parents of 0.65 x reference, and its extra edges made more unguarded
//    splits), but with the fewest-edges remedy it works (2026-11-27, all 20 runs, docs/schemes.md
//    "A floor under the guard"): runs below 0.5x of the input's min 6 -> 4 (certify 7 -> 3) for
//    0.9% more tets (certify 0.4%), the same runs converge, the mean within 0.01; heart2 at eps
//    0.05 takes 23% more tets. Floor 0.55: 5% more tets for no more runs above 0.5x; the floor
//    only where 1:8 could keep it (<= 0.77 x own): no run gains; 3-4 guard rounds with it: 1-2
//    more runs above 0.5x but up to 3.3x Plaza's tets on heart2.
//  - Eight closure rounds, not a fixpoint: on the structured shells the rounds do not die out
//    (heart2 eps 0.05, iteration 3: 189-375 edges in each of its eight rounds), and a fixpoint
//    (up to 25 rounds there) lifts the worst tet where the closure was cut short (4 -> 3 runs
//    below 0.5x) for 0.8% more tets in all, but 34% more on heart2 and no bounded radius
//    (2026-11-27, all 20 runs, docs/schemes.md "Why the closure stops where it does").
//  - The guard takes a last look after the last closure (MarkingRules::final_guard,
//    FinalGuardPass in core/edge_marking.h): a tet whose split the closure left below its
//    threshold gets the fewest more edges that clear it, but only edges that make no tet around
//    them worse than its own threshold and its split before; with no such set the tet is left as
//    it is. A plain third guard pass did not help (its edges made new unguarded splits around the
//    tets it fixed). 2026-11-28, all 20 reproduction runs (docs/schemes.md "The guard's last
//    look"): runs below 0.5x of the input's worst tet 4 -> 1 (T1 blocks eps 0.05 0.37x -> 0.51x,
//    heart2 eps 0.05 0.37x -> 0.51x, Marschner-Lobb blocks eps 0.1 0.45x -> 0.51x; certified
//    3 -> 2) for 0.07% more tets (certified 0.05%); the same stop reasons, no run's worst tet
//    lower, the mean within 0.02 (higher in most). Two or three such passes change nothing more.
//  - The closure marks faces only (Plaza's rule), no longer the longest edge of every tet with
//    a split edge (ClosureRound, core/edge_marking.cc). 2026-11-28, docs/schemes.md "The closure
//    without the tet rule": on the 20 reproduction runs 3.1% fewer tets (above Plaza's in 12 of
//    the 19 both converge on instead of 14), the mean the same or higher, but the worst tet below
//    half the input's in 3 runs instead of 1 (5-tet block and shell meshes, where Plaza's is as
//    low); on the 22 unseen runs 3.1% fewer tets, above Plaza's in 5 instead of 18, no worst tet
//    below 0.5x that was not. Certified: 2.5% and 2.2% fewer tets, above 1.5x Plaza's in 6
//    instead of 7 and 5 instead of 8.
// Every rule reads only the tets around an edge, a bounded number of times per iteration
// (closure and guard: at most 8 + 2 * (1 + 8) = 26 rings of tets, and 2 more for the last look,
// which reads the tets around the edges it adds), so decisions stay local.
struct SchemeRules {
  EdgeTest test = EdgeTest::kMidpoint;
  // The closure and the guard (core/marking_sequence.h); none by default. best_tiling: cut each
  // tet by its best tiling (core/alternative_tilings.h), and let the guard judge that one.
  refine_internal::MarkingRules marking;
};

constexpr int kClosureRounds = 8;
constexpr double kGuardRatio = 0.6;
constexpr int kGuardRounds = 2;
constexpr double kGuardFloor = 0.5;

// quality_reference: RefineOptions::quality_reference, or the input's QualityReference.
SchemeRules RulesOf(const RefineOptions& options, double quality_reference) {
  SchemeRules r;
  if (options.scheme == RefineScheme::kLongestEdge) {
    r.test = options.certify ? EdgeTest::kSegment : EdgeTest::kMidpoint;
    r.marking.closure_rounds = kClosureRounds;
    r.marking.guard_ratio = kGuardRatio;
    r.marking.guard_floor = kGuardFloor * quality_reference;
    r.marking.guard_rounds = kGuardRounds;
    r.marking.best_tiling = true;
    r.marking.final_guard = true;
  }
  return r;
}

int64_t CountSplit(const FillLater<uint8_t>& split) {
  const int64_t n = static_cast<int64_t>(split.size());
  const int64_t blocks = BlockCount(n);
  std::vector<int64_t> counts(blocks, 0);
  ForEachBlock(n, [&](int64_t b, int64_t begin, int64_t end) {
    int64_t c = 0;
    for (int64_t e = begin; e < end; ++e) c += split[e];
    counts[b] = c;
  });
  int64_t total = 0;
  for (int64_t c : counts) total += c;
  return total;
}

absl::StatusOr<RefineResult> RefineInArena(const Volume& volume, const Mesh& input,
                                           const RefineOptions& options) {
  const auto start = Clock::now();
  RefineResult result;
  State state;
  if (absl::Status s = ValidateMesh(input, volume, options.outside, options.orientation,
                                    &state.mesh.tets, &result.tets_reoriented);
      !s.ok()) {
    return s;
  }
  // Only reoriented tets were copied; the points never are until a subdivision makes new ones.
  state.points = &input.points;
  state.tets = state.mesh.tets.empty() ? &input.tets : &state.mesh.tets;
  const std::array<double, 2> range = volume.ValueRange();
  if (options.norm_coeff.has_value()) {
    result.norm_coeff = *options.norm_coeff;
  } else {
    result.norm_coeff = range[1] > range[0] ? range[1] - range[0] : 1.0;
  }
  if (absl::Status s = CheckValuePrecision(result.norm_coeff, range, options.epsilon,
                                           options.norm_coeff.has_value());
      !s.ok()) {
    return s;
  }
  const bool clamp = options.outside == OutsidePolicy::kClamp;
  const double norm = result.norm_coeff;
  const GridGeometry& grid = volume.grid();
  const double min_edge_length = options.min_edge_length.value_or(
      std::min({grid.spacing[0], grid.spacing[1], grid.spacing[2]}) / 64.0);

  const int64_t nv0 = static_cast<int64_t>(input.points.size());
  auto grid_index = [&](int64_t i) {
    const Vec3 u = volume.ContinuousIndex(input.points[i]);
    return clamp ? volume.ClampToGrid(u) : u;
  };
  // Clamping keeps a point in the grid, not in a slab that ends inside it.
  if (const int64_t outside =
          FirstIndexWhere(nv0, [&](int64_t i) { return !volume.Contains(grid_index(i)); });
      outside < nv0) {
    return absl::InvalidArgumentError(
        absl::StrCat("mesh.points[", outside, "] lies outside the volume slab it was sent with"));
  }
  state.mesh.values.resize(nv0);
  ForEachBlock(nv0, [&](int64_t, int64_t begin, int64_t end) {
    for (int64_t i = begin; i < end; ++i) state.mesh.values[i] = volume.SampleIndex(grid_index(i));
  });
  const int64_t nt0 = static_cast<int64_t>(state.tets->size());
  if (nt0 > options.max_tets) {
    return absl::InvalidArgumentError(absl::StrCat(
        "mesh.tets has ", nt0, " tets, more than options.max_tets = ", options.max_tets));
  }
  state.tet_iteration.assign(nt0, 0);
  state.tet_quality.resize(nt0);
  ForEachBlock(nt0, [&](int64_t, int64_t begin, int64_t end) {
    TetQualities(*state.points, *state.tets, begin, end, state.tet_quality.data());
  });
  result.initial_quality = SummarizeQuality(state.tet_quality);

  if (!input.labels.empty()) {
    if (static_cast<int64_t>(input.labels.size()) != nt0) {
      return absl::InvalidArgumentError(
          absl::StrCat("mesh.labels has ", input.labels.size(), " entries for ", nt0, " tets"));
    }
    state.tet_label = input.labels;
  }
  if (options.track_parents) {
    state.tet_parent.resize(nt0);
    for (int64_t t = 0; t < nt0; ++t) state.tet_parent[t] = static_cast<uint32_t>(t);
  }
  if (options.certify) {
    state.tet_lattice_error.assign(nt0, -1.0);
    state.tet_lattice_sum.assign(nt0, std::numeric_limits<double>::quiet_NaN());
  }

  // Only the longest-edge scheme's guard reads it.
  const double quality_reference =
      options.quality_reference.has_value()          ? *options.quality_reference
      : options.scheme == RefineScheme::kLongestEdge ? QualityReference(*state.points, *state.tets)
                                                     : 1.0;
  const SchemeRules rules = RulesOf(options, quality_reference);
  EdgeTestParams params;
  params.test = rules.test;
  params.norm = norm;
  params.epsilon = options.epsilon;
  params.min_edge_length = min_edge_length;
  params.clamp = clamp;
  StepLimits limits;
  limits.max_tets = options.max_tets;
  limits.min_quality = QualityFloor(options.min_quality, result.initial_quality.min);
  limits.clamp = clamp;
  limits.best_tiling = rules.marking.best_tiling;

  CancelFlag cancel(options.should_cancel);
  result.stop_reason = StopReason::kMaxIterations;
  std::optional<KnownEdges> known;
  // The tet-edge array of the iteration before, kept for its memory: AddTetEdges fills it again
  // (see there).
  FillLater<std::array<uint32_t, 6>> spare_tet_edges;
  // What the last subdivision did, for renaming the kept tets' edges instead of looking them up
  // again (UpdateTetEdges): where the old tets went and the old edges' new ids. The lookup was a
  // fifth of a whole call on one thread (T1 brain `--block 4` mesh at eps 0.05, 82 k -> 3.95 M
  // tets in 8 iterations); renaming took its last three iterations from 0.69-1.03 s to
  // 0.42-0.60 s each, interleaved with the commit before (2026-11-24, identical output).
  std::optional<TetSuccession> succession;
  FillLater<uint32_t> remap;
  const auto add_tet_edges = [&](EdgeTable& table) {
    table.tet_edges = std::move(spare_tet_edges);
    if (succession) {
      UpdateTetEdges(*state.tets, *succession, remap, &table);
    } else {
      AddTetEdges(*state.tets, &table);
    }
  };
  bool certified = false;
  for (int iteration = 1;; ++iteration) {
    const auto iteration_start = Clock::now();
    if (cancel.Check()) {
      result.stop_reason = StopReason::kCancelled;
      break;
    }
    // After a subdivision the table is updated from the one before: the same table, for the
    // cost of the children's edges and a copy (UpdateEdgeTable). Measured 2026-11-24 side by side
    // with the full build, one thread, the T1 brain volume's `tetrefine mesh --block 4` mesh at
    // eps 0.05 (82 k -> 3.95 M tets, 8 iterations, identical output): the last three iterations,
    // which change 1-28 k tets, from 1.08-1.21 s to 0.69-0.83 s each, the final edge pass from
    // 0.83-0.89 s to 0.55-0.57 s; bench/core_bench BM_ToConvergence 3.56-4.39 s -> 3.34-3.47 s.
    EdgeTable edges =
        known ? UpdateEdgeTable(known->edges, known->split, *state.tets, state.tet_iteration,
                                iteration - 1, static_cast<int64_t>(state.points->size()), &remap)
              : BuildEdgeTable(*state.tets, static_cast<int64_t>(state.points->size()));
    EdgeErrors errors =
        EvaluateEdges(volume, state, edges, params, known ? &*known : nullptr, cancel);
    known.reset();
    if (cancel.IsSet()) {
      result.stop_reason = StopReason::kCancelled;
      break;
    }
    result.final_max_error = errors.max_error;
    result.final_mean_error = errors.mean_error;
    int64_t failing_tets = 0;
    int64_t short_tets_kept = 0;
    if (options.certify) {
      add_tet_edges(edges);
      failing_tets = refine_internal::MarkFailingTets(
          volume, state, edges, options.lattice_n, params, errors.split, cancel, &short_tets_kept);
      if (cancel.IsSet()) {
        result.stop_reason = StopReason::kCancelled;
        break;
      }
    }
    if (errors.failing == 0 && failing_tets == 0) {
      const bool kept = errors.short_kept > 0 || short_tets_kept > 0;
      result.stop_reason = kept ? StopReason::kMinEdgeLength : StopReason::kConverged;
      certified = options.certify && !kept;
      break;
    }
    if (iteration > options.max_iterations) {
      result.stop_reason = StopReason::kMaxIterations;
      break;
    }
    if (edges.tet_edges.empty()) add_tet_edges(edges);
    IterationStats stats;
    stats.iteration = iteration;
    stats.initial_tets = static_cast<int64_t>(state.tets->size());
    stats.edges = edges.size();
    stats.short_edges_kept = errors.short_kept;
    stats.max_error = errors.max_error;
    stats.mean_error = errors.mean_error;
    stats.max_segment_error = errors.max_segment_error;
    stats.failing_tets = failing_tets;
    FillLater<uint16_t> guard_tilings;
    if (rules.marking.closure_rounds > 0 || rules.marking.guard_rounds > 0) {
      const refine_internal::MarkingCounts marked = refine_internal::CloseAndGuard(
          *state.points, *state.tets, edges, rules.marking, errors.split, cancel, &guard_tilings);
      stats.closure_edges = marked.closure_edges;
      stats.guard_edges = marked.guard_edges;
    }
    // The closure and the guard poll cancellation (each pass reads every tet): their marks are
    // incomplete once it is set.
    if (cancel.IsSet()) {
      result.stop_reason = StopReason::kCancelled;
      break;
    }
    stats.split_edges = CountSplit(errors.split);
    succession.emplace();
    limits.known_tilings = guard_tilings.empty() ? nullptr : &guard_tilings;
    const StepOutcome outcome =
        Subdivide(volume, edges, errors, iteration, limits, cancel, state, stats,
                  &result.next_iteration_tets, &result.next_iteration_min_quality, &*succession);
    if (outcome != StepOutcome::kApplied) {
      result.stop_reason = outcome == StepOutcome::kCancelled   ? StopReason::kCancelled
                           : outcome == StepOutcome::kTetBudget ? StopReason::kTetBudget
                                                                : StopReason::kQualityFloor;
      break;
    }
    spare_tet_edges = std::move(edges.tet_edges);
    known = KnownEdges{std::move(edges), std::move(errors.split), std::move(errors.mid_value),
                       std::move(errors.segment_error)};
    stats.final_tets = static_cast<int64_t>(state.mesh.tets.size());
    stats.quality = SummarizeQuality(state.tet_quality);
    stats.seconds = SecondsSince(iteration_start);
    result.iterations.push_back(stats);
    if (options.on_iteration) {
      // The labels live beside the mesh while refining; lent to it for the callback so that an
      // iteration's mesh carries them like the result does.
      state.mesh.labels.swap(state.tet_label);
      options.on_iteration(stats, state.mesh);
      state.mesh.labels.swap(state.tet_label);
    }
  }
  result.final_quality = SummarizeQuality(state.tet_quality);
  // Without a subdivision the result is the (validated, maybe reoriented) input.
  if (state.points != &state.mesh.points) state.mesh.points = input.points;
  if (state.tets != &state.mesh.tets) state.mesh.tets = input.tets;
  result.mesh = std::move(state.mesh);
  result.mesh.labels = std::move(state.tet_label);
  result.tet_iteration = std::move(state.tet_iteration);
  result.tet_quality = std::move(state.tet_quality);
  result.tet_parent = std::move(state.tet_parent);
  if (options.lattice_n > 0 && result.stop_reason != StopReason::kCancelled) {
    // Certified mode sampled every tet that passed on this lattice already (MarkFailingTets):
    // those are read, not sampled again, and a converged certified call verifies its result for
    // free. Same bits (tests/core/scheme_test.cc). Measured 2026-11-27, one thread, side by side
    // with the commit before, three runs each: the demo at eps 0.05 with --certify (192 k tets)
    // 0.95 -> 0.73 s for the Refine call, 1.13-1.21 -> 0.74-0.89 s for the whole CLI run;
    // bench/core_bench BM_Certified (one iteration, which stops with tets still failing, whose
    // lattices are sampled here) 1.15-1.44 -> 1.01-1.09 s. Memory: a double per tet.
    KnownTetLattices known;
    if (options.certify) known = {&state.tet_lattice_error, &state.tet_lattice_sum};
    result.lattice = SampleLattice(
        volume, result.mesh, options.lattice_n, options.lattice_max_tets, options.lattice_seed,
        norm, options.epsilon, clamp, [&cancel] { return cancel.Check(); }, known);
    // An incomplete lattice is not a result: say the refinement was cancelled.
    if (cancel.IsSet()) result.stop_reason = StopReason::kCancelled;
  } else {
    // No check ran: n = 8 (the default) beside a max of 0 read as a lattice that found nothing
    // (the service's summary said so to Python callers of lattice_n = 0).
    result.lattice.n = 0;
  }
  if (certified) {
    result.certified_max_error = 0.0;
    for (double e : state.tet_lattice_error) {
      result.certified_max_error = std::max(result.certified_max_error, e);
    }
  }
  result.seconds = SecondsSince(start);
  return result;
}

}  // namespace

std::string_view StopReasonName(StopReason r) {
  switch (r) {
    case StopReason::kConverged:
      return "converged";
    case StopReason::kMaxIterations:
      return "max_iterations";
    case StopReason::kTetBudget:
      return "tet_budget";
    case StopReason::kCancelled:
      return "cancelled";
    case StopReason::kQualityFloor:
      return "quality_floor";
    case StopReason::kMinEdgeLength:
      return "min_edge_length";
  }
  return "unknown";
}

absl::StatusOr<RefineResult> Refine(const Volume& volume, const Mesh& mesh,
                                    const RefineOptions& options) {
  if (absl::Status s = ValidateRefineOptions(options); !s.ok()) return s;
  // More threads than TBB's default concurrency (the cores this process may use) gain nothing:
  // TBB caps its workers there anyway, and said so on stderr ("TBB Warning: The number of workers
  // is currently limited to ..."), a line in the middle of `refine --quiet`'s output (outside
  // review, 2026-11-28). The output does not depend on the count.
  const int threads = std::min(options.threads, tbb::info::default_concurrency());
  tbb::task_arena arena(threads > 0 ? threads : tbb::task_arena::automatic);
  absl::StatusOr<RefineResult> result;
  arena.execute([&] { result = RefineInArena(volume, mesh, options); });
  return result;
}

}  // namespace tetrefine
