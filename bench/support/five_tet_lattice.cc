#include "bench/support/five_tet_lattice.h"

#include <cstdint>
#include <vector>

#include "core/five_tet_cell.h"

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
  for (int k = 0; k < cz; ++k) {
    for (int j = 0; j < cy; ++j) {
      for (int i = 0; i < cx; ++i) {
        if (!keep(i, j, k)) continue;
        std::array<uint32_t, 8> c;
        for (int b = 0; b < 8; ++b) c[b] = vertex(i + (b & 1), j + (b >> 1 & 1), k + (b >> 2 & 1));
        AppendFiveTetCell(c, (i + j + k) % 2 == 0, m.points, &m.tets);
      }
    }
  }
  return m;
}

Mesh FiveTetLatticeMesh(const CellLattice& lattice) {
  return FiveTetLatticeMesh(lattice, [](int, int, int) { return true; });
}

}  // namespace tetrefine::bench
