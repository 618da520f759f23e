#include "client/render/plane_section.h"

#include <algorithm>
#include <cmath>

namespace tetrefine::render {
namespace {

constexpr int kEdges[6][2] = {{0, 1}, {0, 2}, {0, 3}, {1, 2}, {1, 3}, {2, 3}};

}  // namespace

bool TetCrossesPlane(const Mesh& mesh, size_t t, const SlicePlane& plane) {
  double lo = INFINITY, hi = -INFINITY;
  for (uint32_t v : mesh.tets[t]) {
    const double d = mesh.points[v][plane.axis];
    lo = std::min(lo, d);
    hi = std::max(hi, d);
  }
  return lo <= plane.position && plane.position <= hi;
}

std::vector<TetSection> PlaneSections(const Mesh& mesh, const SlicePlane& plane) {
  std::vector<TetSection> sections;
  for (size_t t = 0; t < mesh.tets.size(); ++t) {
    if (!TetCrossesPlane(mesh, t, plane)) continue;
    const Tet& tet = mesh.tets[t];
    std::array<double, 4> side{};  // signed distance of each corner from the plane
    for (int c = 0; c < 4; ++c) side[c] = mesh.points[tet[c]][plane.axis] - plane.position;
    std::vector<std::array<double, 2>> corners;
    const auto add = [&](const Vec3& p) { corners.push_back({p[plane.u_axis], p[plane.v_axis]}); };
    for (int c = 0; c < 4; ++c) {
      if (side[c] == 0.0) add(mesh.points[tet[c]]);
    }
    for (const auto& edge : kEdges) {
      const double a = side[edge[0]], b = side[edge[1]];
      // Strictly opposite sides: the crossing is inside the edge (corners on the plane were
      // added above, once).
      if (!((a < 0.0 && b > 0.0) || (a > 0.0 && b < 0.0))) continue;
      const Vec3& p = mesh.points[tet[edge[0]]];
      const Vec3& q = mesh.points[tet[edge[1]]];
      const double s = a / (a - b);
      add({p[0] + s * (q[0] - p[0]), p[1] + s * (q[1] - p[1]), p[2] + s * (q[2] - p[2])});
    }
    if (corners.size() < 2) continue;
    // A plane meets a tet in a convex polygon: order the corners by angle around their mean.
    double cu = 0.0, cv = 0.0;
    for (const auto& p : corners) {
      cu += p[0];
      cv += p[1];
    }
    cu /= static_cast<double>(corners.size());
    cv /= static_cast<double>(corners.size());
    std::sort(corners.begin(), corners.end(), [&](const auto& a, const auto& b) {
      return std::atan2(a[1] - cv, a[0] - cu) < std::atan2(b[1] - cv, b[0] - cu);
    });
    sections.push_back({static_cast<int64_t>(t), std::move(corners)});
  }
  return sections;
}

}  // namespace tetrefine::render
