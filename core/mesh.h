#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "core/volume.h"

namespace tetrefine {

using Tet = std::array<uint32_t, 4>;

// A tetrahedral mesh with one scalar per vertex.
//   points: V x 3 world coordinates (same unit as the volume's grid).
//   tets:   T x 4 indices into points; positive orientation means
//           dot(p1 - p0, cross(p2 - p0, p3 - p0)) > 0.
//   values: V scalars (the field at each vertex); empty on input means "sample the volume".
//   labels: T region labels (a Gmsh physical group, a Medit reference), or empty.
struct Mesh {
  std::vector<Vec3> points;
  std::vector<Tet> tets;
  std::vector<double> values;
  std::vector<int32_t> labels;
};

// Six times the signed volume of tet (a, b, c, d).
double SignedVolume6(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d);

}  // namespace tetrefine
