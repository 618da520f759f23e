#include "bench/support/five_tet_lattice.h"

#include <cstdint>
#include <utility>
#include <vector>

namespace tetrefine::bench {

Mesh FiveTetLatticeMesh(const CellLattice& lattice,
                        const std::function<bool(int i, int j, int k)>& keep) {
  const auto [cx, cy, cz] = lattice.cells;
  const int64_t nx = cx + 1, ny = cy + 1, nz = cz + 1;
  // Lattice vertex -> mesh vertex, assigned on first use so masked meshes stay compact.
  constexpr uint32_t kUnused = UINT32_MAX;
  std::vector<uint32_t> vertex_id(static_cast<size_t>(nx * ny * nz), kUnused);
  Mesh m;
  auto vertex = [&](int i, int j, int k) {
    uint32_t& id = vertex_id[static_cast<size_t>(i + nx * (j + ny * k))];
    if (id == kUnused) {
      id = static_cast<uint32_t>(m.points.size());
      m.points.push_back({lattice.origin[0] + lattice.size[0] * i,
                          lattice.origin[1] + lattice.size[1] * j,
                          lattice.origin[2] + lattice.size[2] * k});
    }
    return id;
  };
  // Even cells cut off corners 1, 2, 4, 7 around the central tet (0, 3, 5, 6); odd cells the
  // mirror image. Corner b of a cell is (i + (b & 1), j + (b >> 1 & 1), k + (b >> 2 & 1)).
  static constexpr std::array<std::array<int, 4>, 5> kEven = {
      {{0, 3, 5, 6}, {1, 0, 3, 5}, {2, 0, 6, 3}, {4, 0, 5, 6}, {7, 3, 6, 5}}};
  static constexpr std::array<std::array<int, 4>, 5> kOdd = {
      {{1, 2, 4, 7}, {0, 1, 4, 2}, {3, 1, 2, 7}, {5, 1, 7, 4}, {6, 2, 4, 7}}};
  for (int k = 0; k < cz; ++k) {
    for (int j = 0; j < cy; ++j) {
      for (int i = 0; i < cx; ++i) {
        if (!keep(i, j, k)) continue;
        uint32_t c[8];
        for (int b = 0; b < 8; ++b) c[b] = vertex(i + (b & 1), j + (b >> 1 & 1), k + (b >> 2 & 1));
        const auto& pattern = ((i + j + k) % 2 == 0) ? kEven : kOdd;
        for (const auto& q : pattern) {
          Tet tet = {c[q[0]], c[q[1]], c[q[2]], c[q[3]]};
          if (SignedVolume6(m.points[tet[0]], m.points[tet[1]], m.points[tet[2]],
                            m.points[tet[3]]) < 0) {
            std::swap(tet[2], tet[3]);
          }
          m.tets.push_back(tet);
        }
      }
    }
  }
  return m;
}

Mesh FiveTetLatticeMesh(const CellLattice& lattice) {
  return FiveTetLatticeMesh(lattice, [](int, int, int) { return true; });
}

}  // namespace tetrefine::bench
