#include "tools/reproduce/case_meshes.h"

#include <cstdint>

#include "bench/support/five_tet_lattice.h"

namespace tetrefine::reproduce {

Mesh MaskedBlockMesh(const Volume& volume, double threshold, int block) {
  const GridGeometry& g = volume.grid();
  bench::CellLattice lattice;
  lattice.origin = g.origin;
  for (int a = 0; a < 3; ++a) {
    lattice.cells[a] = static_cast<int>((g.dims[a] - 1) / block);
    lattice.size[a] = g.spacing[a] * block;
  }
  return bench::FiveTetLatticeMesh(lattice, [&](int i, int j, int k) {
    for (int c = 0; c < 8; ++c) {
      const int64_t x = static_cast<int64_t>(i + (c & 1)) * block;
      const int64_t y = static_cast<int64_t>(j + (c >> 1 & 1)) * block;
      const int64_t z = static_cast<int64_t>(k + (c >> 2 & 1)) * block;
      if (!(volume.At(x, y, z) > threshold)) return false;
    }
    return true;
  });
}

BlockChoice CoarseBlockMesh(const Volume& volume, double threshold, int64_t max_tets) {
  BlockChoice choice;
  for (int block : {2, 3, 4, 5, 6, 8}) {
    choice.block = block;
    choice.mesh = MaskedBlockMesh(volume, threshold, block);
    if (static_cast<int64_t>(choice.mesh.tets.size()) <= max_tets) break;
  }
  return choice;
}

Mesh FitMeshInBox(const Mesh& unit_mesh, const GridGeometry& grid, double margin) {
  Mesh out;
  out.tets = unit_mesh.tets;
  out.points.reserve(unit_mesh.points.size());
  for (const Vec3& p : unit_mesh.points) {
    Vec3 q;
    for (int a = 0; a < 3; ++a) {
      const double extent = static_cast<double>(grid.dims[a] - 1) * grid.spacing[a];
      const double centre = grid.origin[a] + 0.5 * extent;
      q[a] = centre + p[a] * extent * (1.0 - 2.0 * margin);
    }
    out.points.push_back(q);
  }
  return out;
}

}  // namespace tetrefine::reproduce
