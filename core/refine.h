#pragma once

#include <cstdint>
#include <functional>
#include <optional>
#include <string_view>
#include <vector>

#include "absl/status/statusor.h"
#include "core/configuration.h"
#include "core/mesh.h"
#include "core/quality.h"
#include "core/refine_options.h"
#include "core/volume.h"

namespace tetrefine {

// Per-iteration statistics, as the paper reports them (Tables 3-7).
struct IterationStats {
  int iteration = 0;             // 1-based
  int64_t initial_tets = 0;      // INT: tets at the start of the iteration
  int64_t final_tets = 0;        // FNT: tets after the iteration
  int64_t tets_with_error = 0;   // NTwE: tets with at least one split edge
  int64_t edges = 0;             // unique edges evaluated
  int64_t split_edges = 0;       // edges split (failing the test, or added by the closure)
  int64_t short_edges_kept = 0;  // edges above epsilon left whole: shorter than min_edge_length
  double max_error = 0.0;        // max edge-midpoint error at the start of the iteration
  double mean_error = 0.0;       // mean over unique edges of the edge-midpoint error
  // kLongestEdge with certify: the largest discrepancy along any edge at the start of the
  // iteration. 0 otherwise: the midpoint test, which the others use, computes none.
  double max_segment_error = 0.0;
  int64_t closure_edges = 0;  // edges split only because they are a marked face's longest edge
  int64_t guard_edges = 0;    // edges split only by the quality guard (regular refinement)
  // Certified mode: tets whose lattice discrepancy exceeded epsilon at the start of the
  // iteration (each had its longest edge split).
  int64_t failing_tets = 0;
  ConfigurationCounts configurations{};  // tets by configuration (Tables 3 and 4)
  int64_t schonhardt_prisms = 0;         // SP: prisms that needed a Steiner point
  // kLongestEdge: tets cut by another tiling of their faces than the table's, one with a better
  // worst child (core/alternative_tilings.h). Some have one child fewer than Table 1 says (3c:
  // 4, 4a: 5), so FNT = sum of configurations x Table 1's counts + 5 SP - at most this.
  int64_t other_tilings = 0;
  QualityStats quality;  // mean-ratio quality after the iteration
  double seconds = 0.0;  // wall time of the iteration
};

// Discrepancy sampled inside tets on the barycentric lattice of the paper's section 5.1:
// points (i, j, k, l) / n with i + j + k + l = n (165 points for n = 8).
struct LatticeStats {
  int n = 8;  // RefineResult::lattice: 0 when no check ran (lattice_n 0, or cancelled)
  int64_t tets_sampled = 0;
  int64_t points_sampled = 0;
  double max_error = 0.0;
  double mean_error = 0.0;
  double share_above_epsilon = 0.0;  // fraction of sampled points with error > epsilon
  // The same two weighted by tet volume: the discrepancy per unit of volume. Refinement packs
  // small tets where the error is, so per-point figures overweight those regions and can rise
  // while the field gets better everywhere; these do not.
  double volume_mean_error = 0.0;
  double volume_share_above_epsilon = 0.0;
};

enum class StopReason : uint8_t {
  kConverged,      // no edge exceeded epsilon
  kMaxIterations,  // max_iterations reached with edges still above epsilon
  kTetBudget,      // the next iteration would have produced more than max_tets tets
  kCancelled,      // should_cancel returned true
  kQualityFloor,   // the next iteration would have made a tet of quality below min_quality
  // Every edge whose error exceeds epsilon is shorter than min_edge_length, so none is split:
  // what converged means for the edges the refinement may split, but final_max_error is above
  // epsilon (a sweep found such runs reported as converged).
  kMinEdgeLength,
};
std::string_view StopReasonName(StopReason r);

struct RefineResult {
  Mesh mesh;                           // refined mesh, values sampled from the volume
  std::vector<int32_t> tet_iteration;  // per tet: iteration that created it (0 = input)
  std::vector<float> tet_quality;      // per tet: mean-ratio quality eta
  // Per tet: the input tet it lies in (options.track_parents), else empty.
  std::vector<uint32_t> tet_parent;
  std::vector<IterationStats> iterations;
  StopReason stop_reason = StopReason::kConverged;
  int64_t next_iteration_tets = 0;          // for kTetBudget: tets the refused iteration needed
  double next_iteration_min_quality = 0.0;  // for kQualityFloor: its worst tet
  double norm_coeff = 1.0;                  // the normalisation actually used
  QualityStats initial_quality;
  QualityStats final_quality;
  LatticeStats lattice;
  // Edge-midpoint error of the returned mesh (what the next iteration would start from).
  double final_max_error = 0.0;
  double final_mean_error = 0.0;
  int64_t tets_reoriented = 0;  // inverted input tets fixed under kNormalize
  // Certified mode with stop_reason kConverged: the largest discrepancy on the lattice of order
  // lattice_n over every output tet, <= epsilon. Otherwise (not certified, or stopped early)
  // a negative value.
  double certified_max_error = -1.0;
  double seconds = 0.0;
};

// Refines `mesh` inside `volume` until no edge fails the scheme's test (or a limit).
// The output keeps the input's vertices first, with their ids (sharding relies on it), then
// adds each iteration's new vertices; mesh.labels, when given, are inherited by every child.
// Validates the input first: an invalid mesh, volume or option is an InvalidArgument error whose
// message names the offending field and index. Cancellation is not an error: the result says
// kCancelled and holds the mesh as of the last completed iteration.
//
// Guarantees callers rely on (tested):
// - Vertex order: result.mesh.points starts with mesh.points, same ids and same coordinates;
//   the vertices refinement creates follow. Input vertices never move or renumber.
// - Determinism: the output bits (points, tets, values, per-tet arrays, statistics other than
//   seconds) depend only on the inputs and options, not on options.threads or how the work is
//   chunked.
// - Locality, under RefineScheme::kPaper: every split and diagonal decision depends only on its
//   edge or face, never on vertex numbering; only the stops (max_iterations, max_tets,
//   min_quality) look at the whole mesh. kLongestEdge's closure and certify read whole tets and
//   their neighbours, so they do not have it.
// Sharding (sharding/part_merge) relies on all three, hence on kPaper.
absl::StatusOr<RefineResult> Refine(const Volume& volume, const Mesh& mesh,
                                    const RefineOptions& options);

}  // namespace tetrefine
