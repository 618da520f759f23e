#pragma once

#include "core/mesh.h"
#include "core/volume.h"

namespace tetrefine::reproduce {

// A mesh whose points are continuous grid indices, mapped to world through the grid's affine
// (WorldOfIndex); when the direction mirrors (det < 0) each tet's last two vertices are swapped so
// that positively oriented tets stay positive.
Mesh IndexMeshToWorld(Mesh index_mesh, const GridGeometry& grid);

// The paper's liver mesh is a tetrahedrization of the voxels of the organ. Here: blocks of
// block^3 voxels (corners on grid points), each cut into 5 tets, kept when all 8 of the block's
// corner samples exceed `threshold`. block = 1 is the voxel-aligned mesh itself. Built in the
// volume's frame: an oblique grid's blocks are its index-space cells mapped through its affine.
Mesh MaskedBlockMesh(const Volume& volume, double threshold, int block);

// The smallest block in {2, 3, 4, 5, 6, 8} whose masked mesh has at most max_tets tets (the
// largest block when none does): coarse like the paper's initial meshes (1,000-10,000 tets).
struct BlockChoice {
  int block = 0;
  Mesh mesh;
};
BlockChoice CoarseBlockMesh(const Volume& volume, double threshold, int64_t max_tets);

// `unit_mesh` (in [-0.5, 0.5]^3) mapped onto the volume's world box shrunk by `margin` (a share
// of each axis' extent) on every side: vertices at arbitrary, off-grid positions. The map scales
// each axis by a positive factor, so tets keep their orientation. For an oblique grid the box is
// the index box mapped through the grid's affine (tets re-oriented if the direction mirrors).
Mesh FitMeshInBox(const Mesh& unit_mesh, const GridGeometry& grid, double margin);

}  // namespace tetrefine::reproduce
