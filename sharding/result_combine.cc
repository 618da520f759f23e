#include "sharding/result_combine.h"

#include <algorithm>

namespace tetrefine::sharding {
namespace {

// Accumulates quality statistics; means weighted by tet count.
class QualitySum {
 public:
  void Add(const QualityStats& q) {
    if (q.count == 0) return;
    min_ = count_ == 0 ? q.min : std::min(min_, q.min);
    weighted_ += q.mean * static_cast<double>(q.count);
    count_ += q.count;
  }
  QualityStats Get() const {
    QualityStats q;
    q.count = count_;
    q.min = min_;
    q.mean = count_ > 0 ? weighted_ / static_cast<double>(count_) : 0.0;
    return q;
  }

 private:
  double min_ = 0.0;
  double weighted_ = 0.0;
  int64_t count_ = 0;
};

int Completed(const RefineResult& r) { return static_cast<int>(r.iterations.size()); }

// Tets of a part's final mesh (also when the mesh itself was not transferred).
int64_t FinalTets(const RefineResult& r) { return r.final_quality.count; }

}  // namespace

StopReason Settled(const std::vector<const RefineResult*>& parts) {
  const bool short_kept = std::any_of(parts.begin(), parts.end(), [](const RefineResult* r) {
    return r->stop_reason == StopReason::kMinEdgeLength;
  });
  return short_kept ? StopReason::kMinEdgeLength : StopReason::kConverged;
}

WholeStop CombineStops(const std::vector<const RefineResult*>& parts, int max_iterations,
                       int64_t max_tets) {
  for (int i = 1; i <= max_iterations; ++i) {
    int64_t total = 0;
    bool active = false;
    bool floor = false;
    double worst = 1.0;
    for (const RefineResult* r : parts) {
      const int done = Completed(*r);
      if (i <= done) {
        total += r->iterations[i - 1].final_tets;
        active = true;
      } else if (i == done + 1 && r->stop_reason == StopReason::kTetBudget) {
        total += r->next_iteration_tets;
        active = true;
      } else if (i == done + 1 && r->stop_reason == StopReason::kQualityFloor) {
        floor = true;
        worst = std::min(worst, r->next_iteration_min_quality);
        total += FinalTets(*r);  // a lower bound of what iteration i would make
      } else {
        total += FinalTets(*r);  // converged: unchanged from here on
      }
    }
    if (total > max_tets) {
      return {.iterations = i - 1, .reason = StopReason::kTetBudget, .next_iteration_tets = total};
    }
    if (floor) {
      return {.iterations = i - 1,
              .reason = StopReason::kQualityFloor,
              .next_iteration_min_quality = worst};
    }
    if (!active) return {.iterations = i - 1, .reason = Settled(parts)};
  }
  const bool edges_left = std::any_of(parts.begin(), parts.end(), [](const RefineResult* r) {
    return r->stop_reason == StopReason::kMaxIterations;
  });
  return {.iterations = max_iterations,
          .reason = edges_left ? StopReason::kMaxIterations : Settled(parts)};
}

int64_t CountEdges(const Mesh& mesh) {
  // Per vertex, its larger neighbours (compressed rows), then the distinct ones counted.
  const size_t nv = mesh.points.size();
  std::vector<uint32_t> start(nv + 1, 0);
  auto for_each_edge = [&mesh](auto&& f) {
    for (const Tet& t : mesh.tets) {
      for (int a = 0; a < 4; ++a) {
        for (int b = a + 1; b < 4; ++b) f(std::min(t[a], t[b]), std::max(t[a], t[b]));
      }
    }
  };
  for_each_edge([&](uint32_t lo, uint32_t) { ++start[lo + 1]; });
  for (size_t v = 0; v < nv; ++v) start[v + 1] += start[v];
  std::vector<uint32_t> fill(start.begin(), start.end() - 1);
  std::vector<uint32_t> neighbour(start[nv]);
  for_each_edge([&](uint32_t lo, uint32_t hi) { neighbour[fill[lo]++] = hi; });
  int64_t edges = 0;
  for (size_t v = 0; v < nv; ++v) {
    auto begin = neighbour.begin() + start[v];
    auto end = neighbour.begin() + start[v + 1];
    std::sort(begin, end);
    edges += std::unique(begin, end) - begin;
  }
  return edges;
}

std::vector<IterationStats> CombineIterations(const std::vector<const RefineResult*>& parts,
                                              int iterations) {
  std::vector<int64_t> final_edges(parts.size(), -1);  // computed when first needed
  std::vector<IterationStats> out;
  for (int i = 1; i <= iterations; ++i) {
    IterationStats s;
    s.iteration = i;
    QualitySum quality;
    double error_sum = 0.0;
    for (size_t p = 0; p < parts.size(); ++p) {
      const RefineResult& r = *parts[p];
      if (i <= Completed(r)) {
        const IterationStats& x = r.iterations[i - 1];
        s.initial_tets += x.initial_tets;
        s.final_tets += x.final_tets;
        s.tets_with_error += x.tets_with_error;
        s.edges += x.edges;
        s.split_edges += x.split_edges;
        s.short_edges_kept += x.short_edges_kept;
        s.max_error = std::max(s.max_error, x.max_error);
        error_sum += x.mean_error * static_cast<double>(x.edges);
        for (int c = 0; c < kNumConfigurations; ++c) s.configurations[c] += x.configurations[c];
        s.schonhardt_prisms += x.schonhardt_prisms;
        s.other_tilings += x.other_tilings;
        quality.Add(x.quality);
        s.seconds = std::max(s.seconds, x.seconds);
        continue;
      }
      // Converged before iteration i: the unsharded run would still see its tets and edges.
      if (final_edges[p] < 0) final_edges[p] = CountEdges(r.mesh);
      const int64_t tets = FinalTets(r);
      s.initial_tets += tets;
      s.final_tets += tets;
      s.edges += final_edges[p];
      s.max_error = std::max(s.max_error, r.final_max_error);
      error_sum += r.final_mean_error * static_cast<double>(final_edges[p]);
      s.configurations[0] += tets;
      quality.Add(r.final_quality);
    }
    s.mean_error = s.edges > 0 ? error_sum / static_cast<double>(s.edges) : 0.0;
    s.quality = quality.Get();
    out.push_back(s);
  }
  return out;
}

void CombineSummary(const std::vector<const RefineResult*>& parts,
                    const std::vector<double>& part_volumes, RefineResult* out) {
  QualitySum initial, final;
  LatticeStats lattice;
  double error_sum = 0.0, above_sum = 0.0, represented_points = 0.0, represented_volume = 0.0,
         volume_error_sum = 0.0, volume_above_sum = 0.0, final_error_sum = 0.0;
  int64_t final_tets = 0;
  out->final_max_error = 0.0;
  out->tets_reoriented = 0;
  for (size_t p = 0; p < parts.size(); ++p) {
    const RefineResult& r = *parts[p];
    initial.Add(r.initial_quality);
    final.Add(r.final_quality);
    const LatticeStats& l = r.lattice;
    lattice.n = l.n;
    lattice.tets_sampled += l.tets_sampled;
    lattice.points_sampled += l.points_sampled;
    lattice.max_error = std::max(lattice.max_error, l.max_error);
    // Each part's sample stands for the whole part: its means weigh by the part's points and
    // volume, not by what was sampled. Parts sample lattice_max_tets / K tets each whatever
    // their size (SplitLatticeSample), so weighing by the sample would overweight small parts.
    // With every tet sampled the two are the same.
    const double tets = static_cast<double>(FinalTets(r));
    const double points = l.tets_sampled > 0 ? static_cast<double>(l.points_sampled) * tets /
                                                   static_cast<double>(l.tets_sampled)
                                             : 0.0;
    represented_points += points;
    error_sum += l.mean_error * points;
    above_sum += l.share_above_epsilon * points;
    const double volume = l.tets_sampled > 0 ? part_volumes[p] : 0.0;
    represented_volume += volume;
    volume_error_sum += l.volume_mean_error * volume;
    volume_above_sum += l.volume_share_above_epsilon * volume;
    out->final_max_error = std::max(out->final_max_error, r.final_max_error);
    final_error_sum += r.final_mean_error * tets;
    final_tets += FinalTets(r);
    out->tets_reoriented += r.tets_reoriented;
  }
  if (represented_points > 0.0) {
    lattice.mean_error = error_sum / represented_points;
    lattice.share_above_epsilon = above_sum / represented_points;
  }
  if (represented_volume > 0.0) {
    lattice.volume_mean_error = volume_error_sum / represented_volume;
    lattice.volume_share_above_epsilon = volume_above_sum / represented_volume;
  }
  out->initial_quality = initial.Get();
  out->final_quality = final.Get();
  out->lattice = lattice;
  out->final_mean_error = final_tets > 0 ? final_error_sum / static_cast<double>(final_tets) : 0.0;
}

}  // namespace tetrefine::sharding
