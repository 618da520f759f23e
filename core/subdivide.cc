#include "core/subdivide.h"

#include <tbb/parallel_invoke.h>

#include <algorithm>
#include <array>
#include <limits>
#include <vector>

#include "core/alternative_tilings.h"
#include "core/huge_pages.h"
#include "core/parallel.h"
#include "core/quality.h"
#include "core/subdivision_table.h"
#include "core/tet_topology.h"

namespace tetrefine::refine_internal {
StepOutcome Subdivide(const Volume& volume, const EdgeTable& edges, const EdgeErrors& errors,
                      int iteration, const StepLimits& limits, CancelFlag& cancel, State& state,
                      IterationStats& stats, int64_t* next_tets, double* next_quality,
                      TetSuccession* succession) {
  const struct {
    const std::vector<Vec3>& points;
    const std::vector<Tet>& tets;
    const std::vector<double>& values;
  } m{*state.points, *state.tets, state.mesh.values};
  const bool clamp = limits.clamp;
  const int64_t nt = static_cast<int64_t>(m.tets.size());
  const int64_t nv = static_cast<int64_t>(m.points.size());
  const auto& patterns = PatternTable();

  // Pass 1: each tet's subdivision key and child counts, per block.
  // Tiling keys (core/alternative_tilings.h): the subdivision key and which tiling.
  static_assert(kNumTilingKeys <= (1 << 16));
  FillLater<uint16_t> keys(nt);
  FillLater<uint8_t> children_of;
  if (succession != nullptr) children_of.resize(nt);
  const int64_t tet_blocks = BlockCount(nt);
  std::vector<int64_t> child_offset(tet_blocks), steiner_offset(tet_blocks),
      other_tilings(tet_blocks);
  std::vector<ConfigurationCounts> config_counts(tet_blocks);
  ForEachBlock(nt, [&](int64_t b, int64_t begin, int64_t end) {
    if (cancel.Check()) return;
    int64_t children = 0, steiner = 0, other = 0;
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
        if (limits.best_tiling) {
          // The guard's choice stands while the key it chose for is still the tet's: BestTiling
          // reads only the key and the corners. Choosing again was a twentieth of a one-thread
          // file-to-file run.
          const uint16_t known =
              limits.known_tilings != nullptr ? (*limits.known_tilings)[t] : kUnknownTiling;
          key = known != kUnknownTiling && (known & (kNumSubdivisionKeys - 1)) == key
                    ? known
                    : BestTiling(key, {p[0], p[1], p[2], p[3]});
        }
      }
      keys[t] = static_cast<uint16_t>(key);
      const SubdivisionEntry& entry = TilingEntry(key);
      if (succession != nullptr) children_of[t] = key == 0 ? 0 : entry.tet_count;
      children += entry.tet_count;
      steiner += entry.steiner;
      other += (key >> kTilingShift) != 0;
      ++counts[static_cast<int>(patterns[pattern].configuration)];
    }
    child_offset[b] = children;
    steiner_offset[b] = steiner;
    other_tilings[b] = other;
    config_counts[b] = counts;
  });
  if (cancel.IsSet()) return StepOutcome::kCancelled;
  const int64_t total_children = ExclusivePrefixSum(child_offset);
  const int64_t total_steiner = ExclusivePrefixSum(steiner_offset);
  if (total_children > limits.max_tets) {
    *next_tets = total_children;
    return StepOutcome::kTetBudget;
  }
  for (const auto& c : config_counts) {
    for (int i = 0; i < kNumConfigurations; ++i) stats.configurations[i] += c[i];
  }
  stats.schonhardt_prisms = total_steiner;
  for (int64_t n : other_tilings) stats.other_tilings += n;
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
  // Each is offered huge pages before its first write (ReserveHuge): page faults were a third
  // of a whole call. bench/core_bench BM_ToConvergence, one thread, 40k -> 3.88 M tets
  // (2026-11-24): 6.29-6.49 s and 70 k faults as before; 4.10-4.23 s with every allocation
  // advised (GLIBC_TUNABLES=glibc.malloc.hugetlb=1, 7 k faults); with these arrays and the
  // edge table's buckets (core/edge_table.cc) advised, 4.61-4.77 s and 16 k faults against
  // 6.35-7.17 s for the commit before, interleaved.
  auto sized = [](auto& v, int64_t n) {
    ReserveHuge(v, static_cast<size_t>(n));
    v.resize(static_cast<size_t>(n));
  };
  tbb::parallel_invoke(
      [&] {
        ReserveHuge(next.mesh.points, static_cast<size_t>(next_points));
        next.mesh.points.assign(m.points.begin(), m.points.end());
        next.mesh.points.resize(next_points);
      },
      [&] {
        ReserveHuge(next.mesh.values, static_cast<size_t>(next_points));
        next.mesh.values.assign(m.values.begin(), m.values.end());
        next.mesh.values.resize(next_points);
      },
      [&] { sized(next.mesh.tets, total_children); },
      [&] { sized(next.tet_iteration, total_children); },
      [&] { sized(next.tet_quality, total_children); },
      [&] {
        if (!state.tet_label.empty()) sized(next.tet_label, total_children);
        if (!state.tet_parent.empty()) sized(next.tet_parent, total_children);
        if (!state.tet_lattice_error.empty()) sized(next.tet_lattice_error, total_children);
        if (!state.tet_lattice_sum.empty()) sized(next.tet_lattice_sum, total_children);
      });
  const bool labels = !state.tet_label.empty();
  const bool parents = !state.tet_parent.empty();
  const bool certified = !state.tet_lattice_error.empty();
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
    auto write_child = [&](const Tet& child, int64_t t) {
      next.mesh.tets[out] = child;
      next.tet_iteration[out] = iteration;
      if (labels) next.tet_label[out] = state.tet_label[t];
      if (parents) next.tet_parent[out] = state.tet_parent[t];
      if (certified) {
        next.tet_lattice_error[out] = -1.0;
        next.tet_lattice_sum[out] = std::numeric_limits<double>::quiet_NaN();
      }
      ++out;
    };
    for (int64_t t = begin; t < end; ++t) {
      const Tet& tet = m.tets[t];
      if (keys[t] == 0) {
        next.mesh.tets[out] = tet;
        next.tet_iteration[out] = state.tet_iteration[t];
        next.tet_quality[out] = state.tet_quality[t];
        if (labels) next.tet_label[out] = state.tet_label[t];
        if (parents) next.tet_parent[out] = state.tet_parent[t];
        if (certified) {
          next.tet_lattice_error[out] = state.tet_lattice_error[t];
          next.tet_lattice_sum[out] = state.tet_lattice_sum[t];
        }
        ++out;
        continue;
      }
      std::array<uint32_t, kNumLocalPoints> global{};
      for (int c = 0; c < 4; ++c) global[c] = tet[c];
      const auto& te = edges.tet_edges[t];
      // mid_id is written for split edges only (FillLater): read nothing else.
      for (int k = 0; k < 6; ++k) global[4 + k] = errors.split[te[k]] ? mid_id[te[k]] : 0;
      const SubdivisionEntry& entry = TilingEntry(keys[t]);
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
        write_child({global[lt[0]], global[lt[1]], global[lt[2]], global[lt[3]]}, t);
      }
    }
    // The children's qualities in a pass of their own over the block's output (its new tets are
    // the ones of this iteration), a chunk at a time through MeanRatiosAsFloat, whose loop
    // overlaps the values' computations (see there).
    const auto& np = next.mesh.points;
    constexpr int kChunk = 256;
    std::array<MeanRatioParts, kChunk> parts;
    std::array<int64_t, kChunk> where;
    std::array<float, kChunk> quality;
    int pending = 0;
    const auto flush = [&] {
      MeanRatiosAsFloat(parts.data(), pending, quality.data());
      for (int i = 0; i < pending; ++i) {
        next.tet_quality[where[i]] = quality[i];
        block_worst = std::min(block_worst, static_cast<double>(quality[i]));
      }
      pending = 0;
    };
    for (int64_t o = child_offset[b]; o < out; ++o) {
      if (next.tet_iteration[o] != iteration) continue;
      const Tet& child = next.mesh.tets[o];
      const Vec3 &p0 = np[child[0]], &p1 = np[child[1]], &p2 = np[child[2]], &p3 = np[child[3]];
      const double v6 = SignedVolume6(p0, p1, p2, p3);
      if (v6 <= 0.0) block_worst = -1.0;
      parts[pending] = MeanRatioPartsWithVolume6(p0, p1, p2, p3, v6);
      where[pending] = o;
      if (++pending == kChunk) flush();
    }
    flush();
    worst[b] = block_worst;
  });
  if (cancel.IsSet()) return StepOutcome::kCancelled;
  const double worst_quality = *std::min_element(worst.begin(), worst.end());
  if (worst_quality <= 0.0 || worst_quality < limits.min_quality) {
    *next_quality = worst_quality;
    return StepOutcome::kQualityFloor;
  }
  state = std::move(next);
  state.UseOwnMesh();
  if (succession != nullptr) {
    succession->children = std::move(children_of);
    succession->block_start = std::move(child_offset);
  }
  return StepOutcome::kApplied;
}

}  // namespace tetrefine::refine_internal
