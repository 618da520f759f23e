#pragma once

#include <array>
#include <functional>

#include "core/mesh.h"
#include "core/volume.h"

namespace tetrefine::bench {

// A lattice of box cells in world coordinates: cell (i, j, k) spans
// origin + (i, j, k) * size to origin + (i + 1, j + 1, k + 1) * size.
struct CellLattice {
  Vec3 origin{0.0, 0.0, 0.0};
  Vec3 size{1.0, 1.0, 1.0};
  std::array<int, 3> cells{1, 1, 1};
};

// The paper's voxel tetrahedrization: every kept cell cut into 5 positively oriented tets, the
// cut alternating with cell parity so that neighbouring cells split their shared square face by
// the same diagonal (a subset of such cells is therefore still conformal). Only vertices of kept
// cells are in the mesh. No values (Refine samples them).
Mesh FiveTetLatticeMesh(const CellLattice& lattice,
                        const std::function<bool(int i, int j, int k)>& keep);

// Every cell kept.
Mesh FiveTetLatticeMesh(const CellLattice& lattice);

}  // namespace tetrefine::bench
