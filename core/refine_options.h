#pragma once

#include <array>

// The options of one refinement: the one plain options struct, and its one set of limits. Every
// layer that carries options (the wire's request options, the client's call, the CLI's flags)
// embeds or fills this struct, takes its defaults from it and validates it with
// ValidateRefineOptions, so an option is declared, defaulted and bounded here only.

#include <cstdint>
#include <functional>
#include <optional>
#include <string_view>

#include "absl/status/status.h"
#include "core/mesh.h"

namespace tetrefine {

struct IterationStats;  // core/refine.h

// The largest tet budget: edge and vertex ids are 32-bit, and 500 million tets keeps both well
// inside that.
inline constexpr int64_t kMaxTetsCeiling = 500'000'000;

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
// triangulated from its own data; they differ in which edges they split and in how the inside of
// a tet is cut.
enum class RefineScheme : uint8_t {
  // The paper exactly: an edge is split when the discrepancy at its midpoint exceeds epsilon.
  kPaper,
  // The paper's midpoint test, then every face with a split edge also splits its longest edge
  // (longest-edge closure, as in Plaza's scheme), and a tet whose split would make a much
  // flatter child gets the fewest more split edges that avoid it; each tet is cut by
  // the tiling of its faces with the best worst child (core/alternative_tilings.h). It reaches
  // epsilon where the paper's scheme stops with needles. See SchemeRules in core/refine.cc for
  // the measurements behind each rule.
  kLongestEdge,
};
std::string_view RefineSchemeName(RefineScheme s);
// The scheme named `name` ("paper", "longest-edge"); false when there is none.
bool ParseRefineScheme(std::string_view name, RefineScheme* out);

// Options of Refine(), in the spirit of Omega_h's AdaptOpts. The bounds in the comments are
// the ones ValidateRefineOptions enforces. Adding an option: docs/architecture.md, "Where to
// change what".
struct RefineOptions {
  double epsilon = 0.1;  // relative tolerance of eq. 3, finite and > 0
  // >= 0. 32, the cap under which docs/results measures convergence. It was 16 until
  // 2026-11-28: an outside review's run (a tetgen mesh, default scheme) stopped there with edges
  // above epsilon and converges at 18, and a caller who sets no cap should get `converged` where
  // the scheme gets there. The work stays bounded by max_tets; the paper scheme stops at its
  // quality floor long before (13-15 iterations in docs/results).
  int max_iterations = 32;
  // Stop before an iteration that would exceed this. In [1, kMaxTetsCeiling].
  int64_t max_tets = 50'000'000;
  // normCoeff of eq. 3. Unset: the value range (max - min) of the volume given. A caller that
  // sends a slab passes the whole volume's range here. A range of 0 is treated as 1. Set: finite
  // and > 0.
  std::optional<double> norm_coeff;
  OutsidePolicy outside = OutsidePolicy::kReject;
  OrientationPolicy orientation = OrientationPolicy::kReject;
  // >= 0; 0: all cores; more than the cores run as many as the cores. The output does not depend
  // on it.
  int threads = 0;
  // Edges shorter than this (world units) are never split. Unset: 1/64 of the smallest voxel
  // spacing. Why: the paper's scheme splits only marked edges, so the edges joining a new
  // midpoint to far corners stay long; near a feature much sharper than the mesh, those are split
  // again and again at halving distances, the tets become needles, and after ~30 iterations
  // rounding inverts them. Below 1/64 voxel the trilinear field is linear along an edge to
  // within about 1% of its range (a cell-face kink at worst), so splitting further buys little
  // and this bound keeps every tet far from degenerate. The decision stays local to the edge.
  // 0 disables the guard. Set: finite and >= 0.
  std::optional<double> min_edge_length;
  // The scheme can still flatten tets step by step near such a feature (long edges split inside
  // tets that are already slivers). An iteration that would create a tet whose mean-ratio
  // quality is below this, or whose volume is not positive, is not applied: refinement stops
  // before it (kQualityFloor) and the output keeps no degenerate tet. Unset: 1e-6
  // (kDefaultMinQuality), or half the input's worst tet where that is lower (QualityFloor); set,
  // exactly the value given. In [0, 1).
  std::optional<double> min_quality;

  // The default reaches epsilon with bounded quality on real scans, where the paper's scheme
  // stops with needles (docs/schemes.md; SchemeRules in core/refine.cc). kPaper stays available
  // and unchanged to the bit (tests/core/scheme_test.cc pins it).
  RefineScheme scheme = RefineScheme::kLongestEdge;
  // The mean-ratio quality the longest-edge scheme's quality guard keeps every new tet at half of,
  // where it can (SchemeRules in core/refine.cc). Unset: the input mesh's worst tet
  // (QualityReference, core/quality.h). A caller that refines a mesh in pieces or one iteration
  // at a time passes the whole input's value here, so that every piece guards as the whole run
  // would (client/sharding does). Set: in (0, 1].
  std::optional<double> quality_reference;
  // Certified mode: refinement also goes on until the discrepancy at every point of the
  // lattice of order lattice_n (the paper's 165 points for 8) of every tet is <= epsilon; each
  // tet that fails has its longest edge split. The result's `certified_max_error` is then the
  // largest lattice discrepancy over every tet of the output (not a sample): a maximum over
  // those points, not a bound between them. Needs lattice_n >= 4 (orders 1-3 have no point
  // inside a tet; order 1 is the corners, where the discrepancy is 0 by construction).
  bool certify = false;
  // Fill RefineResult::tet_parent (4 bytes per output tet).
  bool track_parents = false;

  // Final lattice verification: lattice_n (in [0, 64]) = 0 skips it. Meshes with more tets than
  // lattice_max_tets (>= 0) are verified on a sample of that many tets drawn with lattice_seed.
  int lattice_n = 8;
  int64_t lattice_max_tets = 200'000;
  uint64_t lattice_seed = 1;

  // Called after each completed iteration with its statistics and the mesh it produced.
  std::function<void(const IterationStats&, const Mesh&)> on_iteration;
  // Polled inside iterations (every few thousand tets) and between them, from worker threads:
  // it must be thread-safe.
  std::function<bool()> should_cancel;
};

// The largest error the statistics may meet, value range / norm_coeff: they sum errors over up
// to 2^63 edges (about 1e19), which must stay below the largest double (1.8e308).
inline constexpr double kMaxRangeOverNorm = 1e280;

// OK when `norm_coeff` suits a volume whose values span `range` ([min, max]): a normal number
// (a subnormal one turns every error into inf) with range / norm_coeff at most
// kMaxRangeOverNorm. Else INVALID_ARGUMENT naming options.norm_coeff, its value and the bound.
// Refine's callers check it once the volume is known (the service when the volume has arrived,
// `tetrefine verify` before it samples).
absl::Status CheckNormCoeffForRange(double norm_coeff, const std::array<double, 2>& range);

// Whether float64 can resolve errors of epsilon x norm_coeff among values as large as the
// volume's `range` (its smallest and largest sample). The interpolations that eq. 1-3 compare
// round at about 16 ulps of the largest magnitude; when that noise exceeds a hundredth of
// epsilon x norm_coeff, or norm_coeff is below 1e-290 (subnormal territory), the errors are
// rounding, not the data: a CLI sweep saw "lattice max 2.0" (impossible in exact arithmetic) and
// refinement to the tet budget for values {1e16, 1e16 + 2}, and 32 M tets for {0, 5e-324}.
// INVALID_ARGUMENT naming the values and what to do (subtract an offset, scale the volume);
// every volume of ordinary data passes (int16 CT: noise 1e-15 of its range). norm_given: the
// caller's options.norm_coeff chose the normalisation, and the message names that field and the
// smallest norm_coeff that passes instead of blaming the volume.
absl::Status CheckValuePrecision(double norm_coeff, const std::array<double, 2>& range,
                                 double epsilon, bool norm_given = false);

inline constexpr double kDefaultMinQuality = 1e-6;

// The quality an iteration's new tets are held to: min_quality when given, else the smaller of
// kDefaultMinQuality and half the input's worst tet (`input_worst`, its mean ratio). Why:
// the floor exists to stop needles the scheme makes; a sliver the input already has is split
// into children about as flat as itself, so a fixed floor above the input's worst stopped every
// scheme before its first iteration, with nothing refined (an outside review, 2026-11-29: a
// TetGen mesh of a jittered grid, worst tet below 1e-6 once fitted, "Stopped after 0
// iterations: quality_floor" at every epsilon; with the relative floor it converges in 8
// iterations, its worst tet no lower than the input's). Half matches the longest-edge guard's
// share of the input's worst. Inputs whose worst tet is at least 2e-6 (every mesh of the
// reproduction) keep 1e-6, so their results are unchanged; a floor the caller sets is theirs
// (min_quality 0.9 still refuses an iteration that makes a tet below 0.9). A sharded run
// computes it from the whole input (client/sharding).
double QualityFloor(const std::optional<double>& min_quality, double input_worst);

// OK, or INVALID_ARGUMENT naming the first offending field and its value, e.g.
// "options.epsilon: must be finite and > 0, got 0". Refine checks its options with this; so does
// the wire layer on a request, before anything else is received.
absl::Status ValidateRefineOptions(const RefineOptions& options);

}  // namespace tetrefine
