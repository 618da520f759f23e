#include "core/five_tet_cell.h"

#include <utility>

namespace tetrefine {

void AppendFiveTetCell(const std::array<uint32_t, 8>& corner, bool even,
                       const std::vector<Vec3>& points, std::vector<Tet>* tets) {
  static constexpr std::array<std::array<int, 4>, 5> kEven = {
      {{0, 3, 5, 6}, {1, 0, 3, 5}, {2, 0, 6, 3}, {4, 0, 5, 6}, {7, 3, 6, 5}}};
  static constexpr std::array<std::array<int, 4>, 5> kOdd = {
      {{1, 2, 4, 7}, {0, 1, 4, 2}, {3, 1, 2, 7}, {5, 1, 7, 4}, {6, 2, 4, 7}}};
  for (const auto& q : even ? kEven : kOdd) {
    Tet tet = {corner[q[0]], corner[q[1]], corner[q[2]], corner[q[3]]};
    if (SignedVolume6(points[tet[0]], points[tet[1]], points[tet[2]], points[tet[3]]) < 0.0) {
      std::swap(tet[2], tet[3]);
    }
    tets->push_back(tet);
  }
}

}  // namespace tetrefine
