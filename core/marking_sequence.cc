#include "core/marking_sequence.h"

#include <algorithm>
#include <optional>

#include "core/alternative_tilings.h"
#include "core/parallel.h"
#include "core/tets_around.h"

namespace tetrefine::refine_internal {
namespace {

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
  if (rules.final_guard && rules.best_tiling && rules.guard_rounds > 0 && !cancel.IsSet()) {
    const std::vector<uint32_t>* visit = next_visit(guard_work);
    if (visit == nullptr || !visit->empty()) {
      if (!around) around.emplace(tets, static_cast<int64_t>(edges.first.size()) - 1);
      counts.guard_edges +=
          FinalGuardPass(points, tets, edges, *around, rules.guard_ratio, rules.guard_floor, split,
                         cancel, visit, nullptr, tilings);
    }
  }
  return counts;
}

}  // namespace tetrefine::refine_internal
