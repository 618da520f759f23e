#include "core/tets_around.h"

#include <algorithm>

namespace tetrefine::refine_internal {

TetsAround::TetsAround(const std::vector<Tet>& tets, int64_t num_vertices) {
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

std::vector<uint32_t> TetsAround::Around(const std::vector<uint32_t>& changed,
                                         const EdgeTable& edges, const std::vector<Tet>& tets,
                                         FillLater<uint8_t>& seen) const {
  std::vector<uint32_t> visit;
  for (uint32_t e : changed) {
    ForEachOnEdge(edges.FirstOf(e), edges.second[e], tets, [&](uint32_t t) {
      if (seen[t] != 0) return;
      seen[t] = 1;
      visit.push_back(t);
    });
  }
  std::sort(visit.begin(), visit.end());
  for (uint32_t t : visit) seen[t] = 0;
  return visit;
}

}  // namespace tetrefine::refine_internal
