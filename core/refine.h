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
#include "core/volume.h"

namespace tetrefine {

// What to do with a mesh vertex outside the volume's sampled box.
enum class OutsidePolicy : uint8_t {
  kReject,  // error naming the first offending vertex (default)
  kClamp,   // sample at the nearest point of the whole grid's box
};

// What to do with a negatively oriented (inverted) input tet.
enum class OrientationPolicy : uint8_t {
  kReject,     // error naming the first inverted tet (default: an inverted tet is a broken mesh)
  kNormalize,  // swap its last two vertices (for meshes written with the opposite convention)
};

// Which subdivision scheme Refine runs. Both split edges at their midpoints and subdivide every
// tet by the paper's 64-case table, so both keep the mesh conformal with every face
// triangulated from its own data; they differ in which edges they split.
enum class RefineScheme : uint8_t {
  // The paper exactly: an edge is split when the discrepancy at its midpoint exceeds epsilon.
  kPaper,
  // The paper's midpoint test, then every tet with a split edge also splits its
  // longest edge (longest-edge closure, as in Rivara's and Plaza's schemes), and a tet whose
  // split would make a much flatter child is refined regularly (1:8) instead. It reaches
  // epsilon where the paper's scheme stops with needles. See SchemeRules in core/refine.cc for
  // the measurements behind each rule.
  kLongestEdge,
};
std::string_view RefineSchemeName(RefineScheme s);
// The scheme named `name` ("paper", "longest-edge"); false when there is none.
bool ParseRefineScheme(std::string_view name, RefineScheme* out);

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
  // kLongestEdge: the largest discrepancy along any edge at the start of the iteration (0 for
  // kPaper, which does not compute it).
  double max_segment_error = 0.0;
  int64_t closure_edges = 0;  // edges split only because they are a marked tet's longest edge
  int64_t guard_edges = 0;    // edges split only by the quality guard (regular refinement)
  // Certified mode: tets whose lattice discrepancy exceeded epsilon at the start of the
  // iteration (each had its longest edge split).
  int64_t failing_tets = 0;
  ConfigurationCounts configurations{};  // tets by configuration (Tables 3 and 4)
  int64_t schonhardt_prisms = 0;         // SP: prisms that needed a Steiner point
  QualityStats quality;                  // mean-ratio quality after the iteration
  double seconds = 0.0;                  // wall time of the iteration
};

// Discrepancy sampled inside tets on the barycentric lattice of the paper's section 5.1:
// points (i, j, k, l) / n with i + j + k + l = n (165 points for n = 8).
struct LatticeStats {
  int n = 8;
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
};
std::string_view StopReasonName(StopReason r);

// Options of refine(), in the spirit of Omega_h's AdaptOpts.
struct RefineOptions {
  double epsilon = 0.1;           // relative tolerance of eq. 3, > 0
  int max_iterations = 16;        // >= 0
  int64_t max_tets = 50'000'000;  // stop before an iteration that would exceed this
  // normCoeff of eq. 3. Unset: the value range (max - min) of the volume given. A caller that
  // sends a slab passes the whole volume's range here. A range of 0 is treated as 1.
  std::optional<double> norm_coeff;
  OutsidePolicy outside = OutsidePolicy::kReject;
  OrientationPolicy orientation = OrientationPolicy::kReject;
  int threads = 0;  // 0: all cores. The output does not depend on it.
  // Edges shorter than this (world units) are never split. Unset: 1/64 of the smallest voxel
  // spacing. Why: the paper's scheme splits only marked edges, so the edges joining a new
  // midpoint to far corners stay long; near a feature much sharper than the mesh, those are split
  // again and again at halving distances, the tets become needles, and after ~30 iterations
  // rounding inverts them. Below 1/64 voxel the trilinear field is linear along an edge to
  // within about 1% of its range (a cell-face kink at worst), so splitting further buys little
  // and this bound keeps every tet far from degenerate. The decision stays local to the edge.
  // 0 disables the guard.
  std::optional<double> min_edge_length;
  // The scheme can still flatten tets step by step near such a feature (long edges split inside
  // tets that are already slivers). An iteration that would create a tet whose mean-ratio
  // quality is below this, or whose volume is not positive, is not applied: refinement stops
  // before it (kQualityFloor) and the output keeps no degenerate tet. In [0, 1).
  double min_quality = 1e-6;

  RefineScheme scheme = RefineScheme::kPaper;
  // Certified mode: refinement also goes on until the discrepancy at every point of the
  // lattice of order lattice_n (the paper's 165 points for 8) of every tet is <= epsilon; each
  // tet that fails has its longest edge split. The result's `certified_max_error` is then the
  // largest lattice discrepancy over every tet of the output (not a sample).
  bool certify = false;
  // Fill RefineResult::tet_parent (4 bytes per output tet).
  bool track_parents = false;

  // Final lattice verification: lattice_n = 0 skips it. Meshes with more tets than
  // lattice_max_tets are verified on a sample of that many tets drawn with lattice_seed.
  int lattice_n = 8;
  int64_t lattice_max_tets = 200'000;
  uint64_t lattice_seed = 1;

  // Called after each completed iteration with its statistics and the mesh it produced.
  std::function<void(const IterationStats&, const Mesh&)> on_iteration;
  // Polled inside iterations (every few thousand tets) and between them, from worker threads:
  // it must be thread-safe.
  std::function<bool()> should_cancel;
};

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
absl::StatusOr<RefineResult> Refine(const Volume& volume, const Mesh& mesh,
                                    const RefineOptions& options);

}  // namespace tetrefine
