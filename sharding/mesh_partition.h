#pragma once

// Splitting a tet mesh into spatially compact parts, each a mesh of its own.

#include <cstdint>
#include <vector>

#include "core/mesh.h"

namespace tetrefine::sharding {

// Splits the tets of `mesh` into `parts` groups by recursive coordinate bisection of the tet
// centroids: each step cuts along the axis of largest centroid extent, in proportion to the parts
// on each side. Ties are broken by tet index, so the split is a pure function of the mesh.
// `parts` is clamped to [1, number of tets]. Each group lists its tets in ascending order.
std::vector<std::vector<uint32_t>> PartitionTets(const Mesh& mesh, int parts);

// One part as a mesh of its own.
struct MeshPart {
  // The part's tets (corner order kept) over its own vertices, numbered in ascending input order.
  // `values` and `labels` are filled only when the input mesh has them.
  Mesh mesh;
  std::vector<uint32_t> input_vertex;  // local vertex -> vertex of the input mesh
  std::vector<uint32_t> input_tet;     // local tet -> tet of the input mesh (its group)
  Vec3 box_lo{0.0, 0.0, 0.0};          // bounding box of the part's vertices (world)
  Vec3 box_hi{0.0, 0.0, 0.0};
};

// Builds the parts for `groups` (from PartitionTets). Tet indices must be in range.
std::vector<MeshPart> ExtractParts(const Mesh& mesh,
                                   const std::vector<std::vector<uint32_t>>& groups);

// Whether p lies in the closed box [lo, hi].
bool InBox(const Vec3& p, const Vec3& lo, const Vec3& hi);

}  // namespace tetrefine::sharding
