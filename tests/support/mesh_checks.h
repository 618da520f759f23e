#pragma once

#include <array>
#include <string>
#include <vector>

#include "core/mesh.h"

namespace tetrefine::testing {

// Volume and boundary area of a mesh (boundary: faces of exactly one tet).
struct MeshMeasure {
  double volume = 0.0;
  double boundary_area = 0.0;
};
MeshMeasure Measure(const Mesh& m);

// Empty when `out` is a conformal refinement of `in`: every tet positive, every face in at most
// two tets lying on opposite sides, no hanging node (CheckConformity), no two vertices at the
// same position, volume and boundary
// area unchanged (relative 1e-9; hanging vertices would add boundary area inside). Otherwise,
// what is wrong.
std::string ConformityProblem(const Mesh& in, const Mesh& out);

// The tets of `m` as lists of corner positions, each sorted, in sorted order: the mesh as
// geometry, equal for two meshes with the same tets whatever their vertex numbering (a sharded
// result's, or a run's on shuffled input).
std::vector<std::array<Vec3, 4>> GeometricTets(const Mesh& m);

// A Medit .mesh reader small enough for tests (Vertices and Tetrahedra only).
Mesh ReadMeditForTest(const std::string& path);

}  // namespace tetrefine::testing
