#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "core/mesh.h"

namespace tetrefine {

// The paper's voxel tetrahedrization of one box cell into five tets. corner[b] is the vertex at
// offset (b & 1, b >> 1 & 1, b >> 2 & 1) of the cell. Even cells ((i + j + k) even) cut off
// corners 1, 2, 4, 7 around the central tet (0, 3, 5, 6), odd cells the mirror image, so
// neighbouring cells split their shared square face by the same diagonal and the mesh is
// conformal. Appends the five tets to *tets, each positively oriented against `points`.
void AppendFiveTetCell(const std::array<uint32_t, 8>& corner, bool even,
                       const std::vector<Vec3>& points, std::vector<Tet>* tets);

}  // namespace tetrefine
