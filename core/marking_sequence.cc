#include "core/marking_sequence.h"

#include <algorithm>
#include <optional>

#include "core/alternative_tilings.h"
#include "core/counting_sort.h"
#include "core/parallel.h"

namespace tetrefine::refine_internal {
namespace {

// The tets around each edge, found through the tets of its smaller vertex. A vertex index (4
// entries per tet) rather than an edge index (6 per tet and a start per edge): it is built while
// the iteration's edge table and marks are alive, and an edge index made the marking the peak of
// memory in late iterations (bench/peak_memory --max_iterations=3, one thread, 2026-11-25:
// 142.0 bytes per output tet at a1f2968, 166.4 with an edge index, 143.2 with this one; one
// iteration 85.3, 89.5, 85.7). After a rule's first pass the edges handed to Around are few, so
// walking their vertices' tets costs little.
class TetsAround {
 public:
  TetsAround(const std::vector<Tet>& tets, int64_t num_vertices) {
    const int64_t nt = static_cast<int64_t>(tets.size());
    layout_ = CountingSort(
        nt, num_vertices,
        [&](int64_t t, auto add) {
          for (uint32_t v : tets[t]) add(v, 1);
        },
        [&](uint64_t total) { tets_.resize(total); },
        [&](int64_t t, auto slot) {
          for (uint32_t v : tets[t]) tets_[slot(v, 1)] = static_cast<uint32_t>(t);
        });
  }

  // The tets with an edge in `changed`, each once, in increasing order (the order a full pass
  // would meet them in: memory is read forwards). `seen` is all zero on entry and on return.
  std::vector<uint32_t> Around(const std::vector<uint32_t>& changed, const EdgeTable& edges,
                               const std::vector<Tet>& tets, FillLater<uint8_t>& seen) const {
    std::vector<uint32_t> visit;
    for (uint32_t e : changed) {
      const uint32_t v = edges.FirstOf(e);
      const uint32_t w = edges.second[e];
      for (uint64_t i = layout_.start[v]; i < layout_.start[v + 1]; ++i) {
        const uint32_t t = tets_[i];
        const Tet& tet = tets[t];
        if (seen[t] == 0 && (tet[0] == w || tet[1] == w || tet[2] == w || tet[3] == w)) {
          seen[t] = 1;
          visit.push_back(t);
        }
      }
    }
    std::sort(visit.begin(), visit.end());
    for (uint32_t t : visit) seen[t] = 0;
    return visit;
  }

 private:
  BucketLayout layout_;
  FillLater<uint32_t> tets_;
};

// Which tets a rule's next pass must visit: all of them the first time, then those around the
// edges marked since its last pass.
class RuleWork {
 public:
  // Null: visit every tet.
  const std::vector<uint32_t>* Next(const std::optional<TetsAround>& around, const EdgeTable& edges,
                                    const std::vector<Tet>& tets, FillLater<uint8_t>& seen) {
    if (!visited_) {
      visited_ = true;
      changed_.clear();
      return nullptr;
    }
    // Nothing marked since: an empty pass (and no index needed for it).
    if (changed_.empty()) {
      visit_.clear();
    } else {
      visit_ = around->Around(changed_, edges, tets, seen);
      changed_.clear();
    }
    return &visit_;
  }
  bool NeedsIndex() const { return visited_ && !changed_.empty(); }
  void Marked(const std::vector<uint32_t>& fresh) {
    changed_.insert(changed_.end(), fresh.begin(), fresh.end());
  }

 private:
  bool visited_ = false;
  std::vector<uint32_t> changed_;  // edges marked since the last pass
  std::vector<uint32_t> visit_;
};

}  // namespace

MarkingCounts CloseAndGuard(const std::vector<Vec3>& points, const std::vector<Tet>& tets,
                            const EdgeTable& edges, const MarkingRules& rules,
                            FillLater<uint8_t>& split, CancelFlag& cancel,
                            FillLater<uint16_t>* tilings) {
  if (tilings != nullptr) {
    if (rules.best_tiling && rules.guard_rounds > 0) {
      tilings->assign(tets.size(), kUnknownTiling);
    } else {
      tilings = nullptr;
    }
  }
  MarkingCounts counts;
  FillLater<uint16_t> targets(tets.size(), kTargetsUnknown);
  std::optional<TetsAround> around;
  FillLater<uint8_t> seen;
  RuleWork closure_work, guard_work;
  std::vector<uint32_t> fresh;
  const auto next_visit = [&](RuleWork& work) {
    if (work.NeedsIndex() && !around) {
      around.emplace(tets, static_cast<int64_t>(edges.first.size()) - 1);
      seen.assign(tets.size(), 0);
    }
    return work.Next(around, edges, tets, seen);
  };
  const auto marked = [&] {
    closure_work.Marked(fresh);
    guard_work.Marked(fresh);
    fresh.clear();
  };
  const auto close = [&] {
    for (int round = 0; round < rules.closure_rounds; ++round) {
      const std::vector<uint32_t>* visit = next_visit(closure_work);
      const int64_t added =
          ClosureRound(points, tets, edges, split, cancel, targets, visit, &fresh);
      if (cancel.IsSet()) return;
      marked();
      counts.closure_edges += added;
      if (added == 0) return;
    }
  };
  close();
  for (int r = 0; r < rules.guard_rounds && !cancel.IsSet(); ++r) {
    const std::vector<uint32_t>* visit = next_visit(guard_work);
    counts.guard_edges += GuardPass(points, tets, edges, rules.guard_ratio, rules.guard_floor,
                                    rules.best_tiling, split, cancel, visit, &fresh, tilings);
    if (cancel.IsSet()) break;
    marked();
    close();
  }
  return counts;
}

}  // namespace tetrefine::refine_internal
