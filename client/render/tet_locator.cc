#include "client/render/tet_locator.h"

#include <algorithm>
#include <cmath>

#include "client/render/plane_section.h"

namespace tetrefine::render {
namespace {

// A point counts as inside a tet when every barycentric coordinate is at least -this: pixel
// centres on a shared face (a structured mesh cut at a grid plane) must find one of the two tets,
// never fall through the crack between them.
constexpr double kInsideTolerance = 1e-9;

struct Box2 {
  double u_lo, u_hi, v_lo, v_hi;
};

Box2 ProjectedBox(const Mesh& mesh, const Tet& tet, const SlicePlane& plane) {
  Box2 box{INFINITY, -INFINITY, INFINITY, -INFINITY};
  for (uint32_t v : tet) {
    const Vec3& p = mesh.points[v];
    box.u_lo = std::min(box.u_lo, p[plane.u_axis]);
    box.u_hi = std::max(box.u_hi, p[plane.u_axis]);
    box.v_lo = std::min(box.v_lo, p[plane.v_axis]);
    box.v_hi = std::max(box.v_hi, p[plane.v_axis]);
  }
  return box;
}

}  // namespace

PlaneTetLocator::PlaneTetLocator(const Mesh& mesh, const SlicePlane& plane)
    : mesh_(mesh), plane_(plane) {
  std::vector<int64_t> crossing;
  for (size_t t = 0; t < mesh.tets.size(); ++t) {
    if (TetCrossesPlane(mesh, t, plane)) crossing.push_back(static_cast<int64_t>(t));
  }
  indexed_ = static_cast<int64_t>(crossing.size());
  // About one tet per cell, spread over the panel in proportion to its sides.
  const double u_extent = plane.u_hi - plane.u_lo, v_extent = plane.v_hi - plane.v_lo;
  const double cells = std::max<double>(1.0, static_cast<double>(crossing.size()));
  const double aspect = u_extent / v_extent;
  cells_u_ = std::clamp(static_cast<int>(std::sqrt(cells * aspect)), 1, 2048);
  cells_v_ = std::clamp(static_cast<int>(std::sqrt(cells / aspect)), 1, 2048);
  cell_u_ = u_extent / cells_u_;
  cell_v_ = v_extent / cells_v_;

  // Two passes (count, then fill) into one flat array.
  const size_t cell_count = static_cast<size_t>(cells_u_) * static_cast<size_t>(cells_v_);
  cell_start_.assign(cell_count + 1, 0);
  std::vector<std::array<int, 4>> ranges(crossing.size());
  for (size_t i = 0; i < crossing.size(); ++i) {
    const Box2 box = ProjectedBox(mesh, mesh.tets[static_cast<size_t>(crossing[i])], plane);
    ranges[i] = {CellU(box.u_lo), CellU(box.u_hi), CellV(box.v_lo), CellV(box.v_hi)};
    for (int cv = ranges[i][2]; cv <= ranges[i][3]; ++cv) {
      for (int cu = ranges[i][0]; cu <= ranges[i][1]; ++cu) {
        ++cell_start_[static_cast<size_t>(cv) * cells_u_ + cu + 1];
      }
    }
  }
  for (size_t c = 0; c < cell_count; ++c) cell_start_[c + 1] += cell_start_[c];
  cell_tets_.resize(static_cast<size_t>(cell_start_.back()));
  std::vector<int64_t> fill(cell_start_.begin(), cell_start_.end() - 1);
  for (size_t i = 0; i < crossing.size(); ++i) {
    for (int cv = ranges[i][2]; cv <= ranges[i][3]; ++cv) {
      for (int cu = ranges[i][0]; cu <= ranges[i][1]; ++cu) {
        cell_tets_[static_cast<size_t>(fill[static_cast<size_t>(cv) * cells_u_ + cu]++)] =
            crossing[i];
      }
    }
  }
}

int PlaneTetLocator::CellU(double u) const {
  const double c = std::floor((u - plane_.u_lo) / cell_u_);
  return static_cast<int>(std::clamp(c, 0.0, static_cast<double>(cells_u_ - 1)));
}

int PlaneTetLocator::CellV(double v) const {
  const double c = std::floor((v - plane_.v_lo) / cell_v_);
  return static_cast<int>(std::clamp(c, 0.0, static_cast<double>(cells_v_ - 1)));
}

std::optional<PlaneTetLocator::Hit> PlaneTetLocator::Locate(const Vec3& p) const {
  const size_t cell =
      static_cast<size_t>(CellV(p[plane_.v_axis])) * cells_u_ + CellU(p[plane_.u_axis]);
  for (int64_t i = cell_start_[cell]; i < cell_start_[cell + 1]; ++i) {
    const int64_t t = cell_tets_[static_cast<size_t>(i)];
    const Tet& tet = mesh_.tets[static_cast<size_t>(t)];
    const Vec3& a = mesh_.points[tet[0]];
    const Vec3& b = mesh_.points[tet[1]];
    const Vec3& c = mesh_.points[tet[2]];
    const Vec3& d = mesh_.points[tet[3]];
    const double total = SignedVolume6(a, b, c, d);
    if (total == 0.0) continue;  // a flat tet contains no point's interpolation
    Hit hit{t,
            {SignedVolume6(p, b, c, d) / total, SignedVolume6(a, p, c, d) / total,
             SignedVolume6(a, b, p, d) / total, SignedVolume6(a, b, c, p) / total}};
    if (std::all_of(hit.weights.begin(), hit.weights.end(),
                    [](double w) { return w >= -kInsideTolerance; })) {
      return hit;
    }
  }
  return std::nullopt;
}

}  // namespace tetrefine::render
