#include "tools/reproduce/case_meshes.h"

#include <cstdint>
#include <utility>

#include "bench/support/five_tet_lattice.h"

namespace tetrefine::reproduce {

Mesh IndexMeshToWorld(Mesh index_mesh, const GridGeometry& grid) {
  for (Vec3& p : index_mesh.points) p = WorldOfIndex(grid, p);
  // A mirroring direction turns every positively oriented tet inside out; swapping two vertices
  // restores the orientation without moving any point.
  if (Determinant(grid.direction) < 0.0) {
    for (Tet& t : index_mesh.tets) std::swap(t[2], t[3]);
  }
  return index_mesh;
}

Mesh MaskedBlockMesh(const Volume& volume, double threshold, int block) {
  const GridGeometry& g = volume.grid();
  bench::CellLattice lattice;
  // Axis-aligned grids keep the world lattice they always had (pinned results); an oblique one
  // is meshed in index space and mapped through its affine, so the mesh lies in its frame.
  const bool axis_aligned = IsIdentityDirection(g.direction);
  lattice.origin = axis_aligned ? g.origin : Vec3{0.0, 0.0, 0.0};
  for (int a = 0; a < 3; ++a) {
    lattice.cells[a] = static_cast<int>((g.dims[a] - 1) / block);
    lattice.size[a] = axis_aligned ? g.spacing[a] * block : static_cast<double>(block);
  }
  Mesh mesh = bench::FiveTetLatticeMesh(lattice, [&](int i, int j, int k) {
    for (int c = 0; c < 8; ++c) {
      const int64_t x = static_cast<int64_t>(i + (c & 1)) * block;
      const int64_t y = static_cast<int64_t>(j + (c >> 1 & 1)) * block;
      const int64_t z = static_cast<int64_t>(k + (c >> 2 & 1)) * block;
      if (!(volume.At(x, y, z) > threshold)) return false;
    }
    return true;
  });
  return axis_aligned ? mesh : IndexMeshToWorld(std::move(mesh), g);
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
  if (IsIdentityDirection(grid.direction)) {
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
  // Oblique: the same fit in index space, then through the grid's affine.
  for (const Vec3& p : unit_mesh.points) {
    Vec3 u;
    for (int a = 0; a < 3; ++a) {
      const double extent = static_cast<double>(grid.dims[a] - 1);
      u[a] = 0.5 * extent + p[a] * extent * (1.0 - 2.0 * margin);
    }
    out.points.push_back(u);
  }
  return IndexMeshToWorld(std::move(out), grid);
}

}  // namespace tetrefine::reproduce
