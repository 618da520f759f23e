#include "core/refine.h"

#include <tbb/parallel_invoke.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <optional>

#include "absl/strings/str_cat.h"
#include "core/edge_table.h"
#include "core/fill_later.h"
#include "core/lattice.h"
#include "core/mesh_validation.h"
#include "core/parallel.h"
#include "core/subdivision_table.h"
#include "core/tet_topology.h"

namespace tetrefine {
namespace {

using Clock = std::chrono::steady_clock;

double SecondsSince(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

// The refinement state carried from one iteration to the next. Until the first subdivision the
// points and tets are the caller's, not a copy (a copy of a large mesh is a serial step that
// showed in the 2-thread profile); `points` and `tets` say where they are.
struct State {
  Mesh mesh;  // values always; points and tets once a subdivision has made them
  const std::vector<Vec3>* points = nullptr;
  const std::vector<Tet>* tets = nullptr;
  std::vector<int32_t> tet_iteration;
  std::vector<float> tet_quality;

  // Points `points` and `tets` at the state's own mesh (after it was made or moved).
  void UseOwnMesh() {
    points = &mesh.points;
    tets = &mesh.tets;
  }
};

absl::Status CheckOptions(const RefineOptions& o) {
  if (!(o.epsilon > 0.0) || !std::isfinite(o.epsilon)) {
    return absl::InvalidArgumentError(
        absl::StrCat("options.epsilon = ", o.epsilon, ": must be finite and > 0"));
  }
  if (o.max_iterations < 0) {
    return absl::InvalidArgumentError(
        absl::StrCat("options.max_iterations = ", o.max_iterations, ": must be >= 0"));
  }
  // Edge and vertex ids are 32-bit; 500 million tets keeps both well inside that.
  constexpr int64_t kTetCeiling = 500'000'000;
  if (o.max_tets < 1 || o.max_tets > kTetCeiling) {
    return absl::InvalidArgumentError(
        absl::StrCat("options.max_tets = ", o.max_tets, ": must be in [1, ", kTetCeiling, "]"));
  }
  if (o.norm_coeff.has_value() && (!(*o.norm_coeff > 0.0) || !std::isfinite(*o.norm_coeff))) {
    return absl::InvalidArgumentError(
        absl::StrCat("options.norm_coeff = ", *o.norm_coeff, ": must be finite and > 0"));
  }
  if (o.lattice_n < 0 || o.lattice_n > 64) {
    return absl::InvalidArgumentError(
        absl::StrCat("options.lattice_n = ", o.lattice_n, ": must be in [0, 64]"));
  }
  if (o.min_edge_length.has_value() &&
      (!(*o.min_edge_length >= 0.0) || !std::isfinite(*o.min_edge_length))) {
    return absl::InvalidArgumentError(absl::StrCat("options.min_edge_length = ", *o.min_edge_length,
                                                   ": must be finite and >= 0"));
  }
  if (!(o.min_quality >= 0.0 && o.min_quality < 1.0)) {
    return absl::InvalidArgumentError(
        absl::StrCat("options.min_quality = ", o.min_quality, ": must be in [0, 1)"));
  }
  if (o.threads < 0) {
    return absl::InvalidArgumentError(
        absl::StrCat("options.threads = ", o.threads, ": must be >= 0 (0: all cores)"));
  }
  return absl::OkStatus();
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

float TetQuality(const std::vector<Vec3>& p, const Tet& t) {
  return static_cast<float>(MeanRatio(p[t[0]], p[t[1]], p[t[2]], p[t[3]]));
}

// Trilinear value at a point inside the mesh's hull (a midpoint or a Steiner point).
double SampleInside(const Volume& volume, const Vec3& p, bool clamp) {
  Vec3 u = volume.ContinuousIndex(p);
  if (clamp) u = volume.ClampToGrid(u);
  return volume.SampleIndex(u);
}

Vec3 Midpoint(const Vec3& a, const Vec3& b) {
  return {0.5 * (a[0] + b[0]), 0.5 * (a[1] + b[1]), 0.5 * (a[2] + b[2])};
}

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

// Edge-midpoint errors of every unique edge (eq. 3), with the midpoint values kept for the new
// vertices.
struct EdgeErrors {
  FillLater<double> mid_value;
  FillLater<uint8_t> split;
  int64_t split_count = 0;
  int64_t short_kept = 0;
  double max_error = 0.0;
  double mean_error = 0.0;
};

// The previous iteration's edges and their midpoint values. Subdivision keeps the old vertices'
// ids and values, and joins two old vertices only along an old edge it did not split (a child's
// corners are its parent's corners, edge midpoints and Steiner point), so every edge of the
// refined mesh between two old vertices is in this table with the same midpoint value. The next
// evaluation reads those instead of sampling the volume again: the same bits, and most of a
// late iteration's edges are such edges.
struct KnownMidpoints {
  EdgeTable edges;  // without tet_edges
  FillLater<double> mid_value;
};

EdgeErrors EvaluateEdges(const Volume& volume, const State& m, const EdgeTable& edges, double norm,
                         double epsilon, double min_edge_length, bool clamp,
                         const KnownMidpoints* known, CancelFlag& cancel) {
  const double min_length2 = min_edge_length * min_edge_length;
  EdgeErrors out;
  const std::vector<Vec3>& points = *m.points;
  const std::vector<double>& values = m.mesh.values;
  const int64_t nv = static_cast<int64_t>(points.size());
  out.mid_value.resize(edges.size());
  out.split.resize(edges.size());
  const int64_t blocks = BlockCount(nv);
  std::vector<double> sums(blocks, 0.0), maxs(blocks, 0.0);
  std::vector<int64_t> splits(blocks, 0), kept(blocks, 0);
  ForEachBlock(nv, [&](int64_t b, int64_t begin, int64_t end) {
    if (cancel.Check()) return;
    double s = 0.0, mx = 0.0;
    int64_t n_split = 0, n_kept = 0;
    for (int64_t v = begin; v < end; ++v) {
      // v's known edges, walked forward alongside its sorted new ones.
      const uint32_t* kp = nullptr;
      const uint32_t* ke = nullptr;
      if (known != nullptr && v + 1 < static_cast<int64_t>(known->edges.first.size())) {
        kp = known->edges.second.data() + known->edges.first[v];
        ke = known->edges.second.data() + known->edges.first[v + 1];
      }
      for (uint32_t e = edges.first[v]; e < edges.first[v + 1]; ++e) {
        const uint32_t w = edges.second[e];
        while (kp < ke && *kp < w) ++kp;
        const double real = kp < ke && *kp == w
                                ? known->mid_value[kp - known->edges.second.data()]
                                : SampleInside(volume, Midpoint(points[v], points[w]), clamp);
        const double error = std::abs(real - 0.5 * (values[v] + values[w])) / norm;
        out.mid_value[e] = real;
        bool split = error > epsilon;
        if (split && min_length2 > 0.0) {
          const Vec3& a = points[v];
          const Vec3& c = points[w];
          const double dx = a[0] - c[0], dy = a[1] - c[1], dz = a[2] - c[2];
          if (dx * dx + dy * dy + dz * dz < min_length2) {
            split = false;
            ++n_kept;
          }
        }
        out.split[e] = split;
        n_split += split;
        s += error;
        mx = std::max(mx, error);
      }
    }
    sums[b] = s;
    maxs[b] = mx;
    splits[b] = n_split;
    kept[b] = n_kept;
  });
  double sum = 0.0;
  for (int64_t b = 0; b < blocks; ++b) {
    sum += sums[b];
    out.max_error = std::max(out.max_error, maxs[b]);
    out.split_count += splits[b];
    out.short_kept += kept[b];
  }
  out.mean_error = edges.size() > 0 ? sum / static_cast<double>(edges.size()) : 0.0;
  return out;
}

enum class StepOutcome { kApplied, kCancelled, kTetBudget, kQualityFloor };

// One subdivision step. Leaves `state` alone unless it returns kApplied; for kTetBudget
// *next_tets says how many tets it needed, for kQualityFloor *next_quality its worst tet.
StepOutcome Subdivide(const Volume& volume, const EdgeTable& edges, const EdgeErrors& errors,
                      int iteration, const RefineOptions& options, CancelFlag& cancel, State& state,
                      IterationStats& stats, int64_t* next_tets, double* next_quality) {
  const struct {
    const std::vector<Vec3>& points;
    const std::vector<Tet>& tets;
    const std::vector<double>& values;
  } m{*state.points, *state.tets, state.mesh.values};
  const bool clamp = options.outside == OutsidePolicy::kClamp;
  const int64_t nt = static_cast<int64_t>(m.tets.size());
  const int64_t nv = static_cast<int64_t>(m.points.size());
  const auto& table = SubdivisionTable();
  const auto& patterns = PatternTable();

  // Pass 1: each tet's subdivision key and child counts, per block.
  FillLater<uint16_t> keys(nt);
  const int64_t tet_blocks = BlockCount(nt);
  std::vector<int64_t> child_offset(tet_blocks), steiner_offset(tet_blocks);
  std::vector<ConfigurationCounts> config_counts(tet_blocks);
  ForEachBlock(nt, [&](int64_t b, int64_t begin, int64_t end) {
    if (cancel.Check()) return;
    int64_t children = 0, steiner = 0;
    ConfigurationCounts counts{};
    for (int64_t t = begin; t < end; ++t) {
      const Tet& tet = m.tets[t];
      const auto& te = edges.tet_edges[t];
      uint32_t pattern = 0;
      for (int k = 0; k < 6; ++k) pattern |= errors.split[te[k]] ? EdgeBit(k) : 0u;
      uint32_t key = 0;
      if (pattern != 0) {
        std::array<Vec3, 10> p;
        for (int c = 0; c < 4; ++c) p[c] = m.points[tet[c]];
        for (int k = 0; k < 6; ++k) {
          if ((pattern & EdgeBit(k)) != 0) {
            p[4 + k] = Midpoint(p[kTetEdges[k][0]], p[kTetEdges[k][1]]);
          }
        }
        key = SubdivisionKey(pattern, p);
      }
      keys[t] = static_cast<uint16_t>(key);
      const SubdivisionEntry& entry = table[key];
      children += entry.tet_count;
      steiner += entry.steiner;
      ++counts[static_cast<int>(patterns[pattern].configuration)];
    }
    child_offset[b] = children;
    steiner_offset[b] = steiner;
    config_counts[b] = counts;
  });
  if (cancel.IsSet()) return StepOutcome::kCancelled;
  const int64_t total_children = ExclusivePrefixSum(child_offset);
  const int64_t total_steiner = ExclusivePrefixSum(steiner_offset);
  if (total_children > options.max_tets) {
    *next_tets = total_children;
    return StepOutcome::kTetBudget;
  }
  for (const auto& c : config_counts) {
    for (int i = 0; i < kNumConfigurations; ++i) stats.configurations[i] += c[i];
  }
  stats.schonhardt_prisms = total_steiner;
  stats.tets_with_error = nt - stats.configurations[0];

  // New vertex ids: midpoints in edge order after the old vertices, then Steiner points in tet
  // order.
  const int64_t vertex_blocks = BlockCount(nv);
  std::vector<int64_t> mid_offset(vertex_blocks);
  ForEachBlock(nv, [&](int64_t b, int64_t begin, int64_t end) {
    int64_t n = 0;
    for (uint32_t e = edges.first[begin]; e < edges.first[end]; ++e) n += errors.split[e];
    mid_offset[b] = n;
  });
  const int64_t total_mid = ExclusivePrefixSum(mid_offset);
  FillLater<uint32_t> mid_id(edges.size());
  // The output arrays are the mesh's public std::vectors, which zero their elements on one
  // thread (and take the page faults there) before the passes below overwrite them: that was
  // the largest serial step of an iteration. Allocating them side by side cuts it by the number
  // of workers.
  State next;
  const int64_t next_points = nv + total_mid + total_steiner;
  tbb::parallel_invoke(
      [&] {
        next.mesh.points.reserve(next_points);
        next.mesh.points.assign(m.points.begin(), m.points.end());
        next.mesh.points.resize(next_points);
      },
      [&] {
        next.mesh.values.reserve(next_points);
        next.mesh.values.assign(m.values.begin(), m.values.end());
        next.mesh.values.resize(next_points);
      },
      [&] { next.mesh.tets.resize(total_children); },
      [&] { next.tet_iteration.resize(total_children); },
      [&] { next.tet_quality.resize(total_children); });
  ForEachBlock(nv, [&](int64_t b, int64_t begin, int64_t end) {
    int64_t id = nv + mid_offset[b];
    for (int64_t v = begin; v < end; ++v) {
      for (uint32_t e = edges.first[v]; e < edges.first[v + 1]; ++e) {
        if (!errors.split[e]) continue;
        mid_id[e] = static_cast<uint32_t>(id);
        next.mesh.points[id] = Midpoint(m.points[v], m.points[edges.second[e]]);
        next.mesh.values[id] = errors.mid_value[e];
        ++id;
      }
    }
  });

  // Pass 2: write the children.
  const int64_t steiner_base = nv + total_mid;
  std::vector<double> worst(tet_blocks, 1.0);
  ForEachBlock(nt, [&](int64_t b, int64_t begin, int64_t end) {
    if (cancel.Check()) return;
    double block_worst = 1.0;
    int64_t out = child_offset[b];
    int64_t steiner_id = steiner_base + steiner_offset[b];
    for (int64_t t = begin; t < end; ++t) {
      const Tet& tet = m.tets[t];
      if (keys[t] == 0) {
        next.mesh.tets[out] = tet;
        next.tet_iteration[out] = state.tet_iteration[t];
        next.tet_quality[out] = state.tet_quality[t];
        ++out;
        continue;
      }
      const SubdivisionEntry& entry = table[keys[t]];
      std::array<uint32_t, kNumLocalPoints> global{};
      for (int c = 0; c < 4; ++c) global[c] = tet[c];
      const auto& te = edges.tet_edges[t];
      // mid_id is written for split edges only (FillLater): read nothing else.
      for (int k = 0; k < 6; ++k) global[4 + k] = errors.split[te[k]] ? mid_id[te[k]] : 0;
      if (entry.steiner) {
        std::array<Vec3, 6> pts;
        for (int i = 0; i < 6; ++i) pts[i] = next.mesh.points[global[entry.steiner_of[i]]];
        const Vec3 s = SteinerPoint(pts);
        global[kSteinerLocal] = static_cast<uint32_t>(steiner_id);
        next.mesh.points[steiner_id] = s;
        next.mesh.values[steiner_id] = SampleInside(volume, s, clamp);
        ++steiner_id;
      }
      for (int i = 0; i < entry.tet_count; ++i) {
        const auto& lt = entry.tets[i];
        const Tet child = {global[lt[0]], global[lt[1]], global[lt[2]], global[lt[3]]};
        next.mesh.tets[out] = child;
        next.tet_iteration[out] = iteration;
        const auto& np = next.mesh.points;
        const Vec3 &a = np[child[0]], &b = np[child[1]], &c = np[child[2]], &d = np[child[3]];
        const double v6 = SignedVolume6(a, b, c, d);
        const float q = static_cast<float>(MeanRatioWithVolume6(a, b, c, d, v6));
        next.tet_quality[out] = q;
        if (v6 <= 0.0) block_worst = -1.0;
        block_worst = std::min(block_worst, static_cast<double>(q));
        ++out;
      }
    }
    worst[b] = block_worst;
  });
  if (cancel.IsSet()) return StepOutcome::kCancelled;
  const double worst_quality = *std::min_element(worst.begin(), worst.end());
  if (worst_quality <= 0.0 || worst_quality < options.min_quality) {
    *next_quality = worst_quality;
    return StepOutcome::kQualityFloor;
  }
  state = std::move(next);
  state.UseOwnMesh();
  return StepOutcome::kApplied;
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
  if (options.norm_coeff.has_value()) {
    result.norm_coeff = *options.norm_coeff;
  } else {
    const auto range = volume.ValueRange();
    result.norm_coeff = range[1] > range[0] ? range[1] - range[0] : 1.0;
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
    for (int64_t t = begin; t < end; ++t) {
      state.tet_quality[t] = TetQuality(*state.points, (*state.tets)[t]);
    }
  });
  result.initial_quality = SummarizeQuality(state.tet_quality);

  CancelFlag cancel(options.should_cancel);
  result.stop_reason = StopReason::kMaxIterations;
  bool finished = false;
  std::optional<KnownMidpoints> known;
  for (int iteration = 1; !finished; ++iteration) {
    const auto iteration_start = Clock::now();
    if (cancel.Check()) {
      result.stop_reason = StopReason::kCancelled;
      break;
    }
    EdgeTable edges = BuildEdgeTable(*state.tets, static_cast<int64_t>(state.points->size()));
    EdgeErrors errors = EvaluateEdges(volume, state, edges, norm, options.epsilon, min_edge_length,
                                      clamp, known ? &*known : nullptr, cancel);
    known.reset();
    if (cancel.IsSet()) {
      result.stop_reason = StopReason::kCancelled;
      break;
    }
    result.final_max_error = errors.max_error;
    result.final_mean_error = errors.mean_error;
    if (errors.split_count == 0) {
      result.stop_reason = StopReason::kConverged;
      break;
    }
    if (iteration > options.max_iterations) {
      result.stop_reason = StopReason::kMaxIterations;
      break;
    }
    AddTetEdges(*state.tets, &edges);
    IterationStats stats;
    stats.iteration = iteration;
    stats.initial_tets = static_cast<int64_t>(state.tets->size());
    stats.edges = edges.size();
    stats.split_edges = errors.split_count;
    stats.short_edges_kept = errors.short_kept;
    stats.max_error = errors.max_error;
    stats.mean_error = errors.mean_error;
    const StepOutcome outcome =
        Subdivide(volume, edges, errors, iteration, options, cancel, state, stats,
                  &result.next_iteration_tets, &result.next_iteration_min_quality);
    if (outcome != StepOutcome::kApplied) {
      result.stop_reason = outcome == StepOutcome::kCancelled   ? StopReason::kCancelled
                           : outcome == StepOutcome::kTetBudget ? StopReason::kTetBudget
                                                                : StopReason::kQualityFloor;
      break;
    }
    edges.tet_edges = {};
    known = KnownMidpoints{std::move(edges), std::move(errors.mid_value)};
    stats.final_tets = static_cast<int64_t>(state.mesh.tets.size());
    stats.quality = SummarizeQuality(state.tet_quality);
    stats.seconds = SecondsSince(iteration_start);
    result.iterations.push_back(stats);
    if (options.on_iteration) options.on_iteration(stats, state.mesh);
  }
  result.final_quality = SummarizeQuality(state.tet_quality);
  // Without a subdivision the result is the (validated, maybe reoriented) input.
  if (state.points != &state.mesh.points) state.mesh.points = input.points;
  if (state.tets != &state.mesh.tets) state.mesh.tets = input.tets;
  result.mesh = std::move(state.mesh);
  result.tet_iteration = std::move(state.tet_iteration);
  result.tet_quality = std::move(state.tet_quality);
  if (options.lattice_n > 0 && result.stop_reason != StopReason::kCancelled) {
    result.lattice = SampleLattice(volume, result.mesh, options.lattice_n, options.lattice_max_tets,
                                   options.lattice_seed, norm, options.epsilon, clamp,
                                   [&cancel] { return cancel.Check(); });
    // An incomplete lattice is not a result: say the refinement was cancelled.
    if (cancel.IsSet()) result.stop_reason = StopReason::kCancelled;
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
  }
  return "unknown";
}

absl::StatusOr<RefineResult> Refine(const Volume& volume, const Mesh& mesh,
                                    const RefineOptions& options) {
  if (absl::Status s = CheckOptions(options); !s.ok()) return s;
  tbb::task_arena arena(options.threads > 0 ? options.threads : tbb::task_arena::automatic);
  absl::StatusOr<RefineResult> result;
  arena.execute([&] { result = RefineInArena(volume, mesh, options); });
  return result;
}

}  // namespace tetrefine
