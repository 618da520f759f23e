#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <vector>

#include "client/render/slice_plane.h"
#include "core/mesh.h"

namespace tetrefine::render {

// Finds the tet of `mesh` that contains a point of one plane. Only the tets the plane cuts are
// indexed, in a uniform grid over the plane whose cells list every tet whose bounding box
// (projected onto the plane) overlaps them: about one tet per cell, so a lookup tests a handful
// of tets whatever the mesh size.
class PlaneTetLocator {
 public:
  // Keeps references: `mesh` and `plane` must outlive the locator.
  PlaneTetLocator(const Mesh& mesh, const SlicePlane& plane);

  struct Hit {
    int64_t tet = 0;
    std::array<double, 4> weights{};  // barycentric coordinates of the point, summing to 1
  };

  // The tet containing world point p (on the plane), the first in tet order when p lies on a
  // shared face; nullopt when no tet does (outside the mesh, or in a hole).
  std::optional<Hit> Locate(const Vec3& p) const;

  int64_t indexed_tets() const { return indexed_; }

 private:
  int CellU(double u) const;
  int CellV(double v) const;

  const Mesh& mesh_;
  const SlicePlane& plane_;
  int cells_u_ = 1, cells_v_ = 1;
  double cell_u_ = 1.0, cell_v_ = 1.0;  // world size of a cell
  std::vector<int64_t> cell_start_;     // CSR: tets of cell c are cell_tets_[start[c], start[c+1])
  std::vector<int64_t> cell_tets_;
  int64_t indexed_ = 0;
};

}  // namespace tetrefine::render
