#include "core/marking_sequence.h"

#include <algorithm>
#include <optional>

#include "core/alternative_tilings.h"
#include "core/counting_sort.h"
#include "core/parallel.h"

namespace tetrefine::refine_internal {
namespace {

// The tets around each edge: edge e's tets are tets[start[e] .. start[e + 1]).
class EdgeTets {
 public:
  EdgeTets(const EdgeTable& edges, int64_t num_tets) {
    const auto& tet_edges = edges.tet_edges;
    layout_ = CountingSort(
        num_tets, edges.size(),
        [&](int64_t t, auto add) {
          for (uint32_t e : tet_edges[t]) add(e, 1);
        },
        [&](uint64_t total) { tets_.resize(total); },
        [&](int64_t t, auto slot) {
          for (uint32_t e : tet_edges[t]) tets_[slot(e, 1)] = static_cast<uint32_t>(t);
        });
  }

  // The tets with an edge in `changed`, each once, in increasing order (the order the full pass
  // would meet them in: memory is read forwards). `seen` is all zero on entry and on return.
  std::vector<uint32_t> Around(const std::vector<uint32_t>& changed,
                               FillLater<uint8_t>& seen) const {
    std::vector<uint32_t> visit;
    for (uint32_t e : changed) {
      for (uint64_t i = layout_.start[e]; i < layout_.start[e + 1]; ++i) {
        const uint32_t t = tets_[i];
        if (seen[t] == 0) {
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
  const std::vector<uint32_t>* Next(const std::optional<EdgeTets>& around,
                                    FillLater<uint8_t>& seen) {
    if (!visited_) {
      visited_ = true;
      changed_.clear();
      return nullptr;
    }
    visit_ = around->Around(changed_, seen);
    changed_.clear();
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
  const int64_t nt = static_cast<int64_t>(tets.size());
  if (tilings != nullptr) {
    if (rules.best_tiling && rules.guard_rounds > 0) {
      tilings->assign(tets.size(), kUnknownTiling);
    } else {
      tilings = nullptr;
    }
  }
  MarkingCounts counts;
  FillLater<uint16_t> targets(tets.size(), kTargetsUnknown);
  std::optional<EdgeTets> around;
  FillLater<uint8_t> seen;
  RuleWork closure_work, guard_work;
  std::vector<uint32_t> fresh;
  const auto next_visit = [&](RuleWork& work) {
    if (work.NeedsIndex() && !around) {
      around.emplace(edges, nt);
      seen.assign(tets.size(), 0);
    }
    return work.Next(around, seen);
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
    counts.guard_edges += GuardPass(points, tets, edges, rules.guard_ratio, rules.best_tiling,
                                    split, cancel, visit, &fresh, tilings);
    if (cancel.IsSet()) break;
    marked();
    close();
  }
  return counts;
}

}  // namespace tetrefine::refine_internal
