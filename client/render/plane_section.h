#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "client/render/slice_plane.h"
#include "core/mesh.h"

namespace tetrefine::render {

// Where one tet meets the plane: the convex polygon of the intersection (3 or 4 corners; 2 when
// only an edge lies on the plane), corners in in-plane world coordinates (u, v) in order around
// the polygon.
struct TetSection {
  int64_t tet = 0;
  std::vector<std::array<double, 2>> corners;
};

// True when tet t's extent along the plane's axis contains the plane's position.
bool TetCrossesPlane(const Mesh& mesh, size_t t, const SlicePlane& plane);

// The section of every tet the plane cuts (a tet that only touches the plane at one vertex has
// none), in tet order: the mesh's edges on the plane are the sides of these polygons.
std::vector<TetSection> PlaneSections(const Mesh& mesh, const SlicePlane& plane);

}  // namespace tetrefine::render
