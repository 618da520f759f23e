#include "client/render/slice_plane.h"

#include <algorithm>
#include <cmath>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"

namespace tetrefine::render {
namespace {

constexpr const char* kAxisNames[] = {"x", "y", "z"};

}  // namespace

Vec3 SlicePlane::PixelCentre(int column, int row) const {
  Vec3 p{};
  p[axis] = position;
  p[u_axis] = u_lo + (column + 0.5) * (u_hi - u_lo) / width;
  p[v_axis] = v_hi - (row + 0.5) * (v_hi - v_lo) / height;
  return p;
}

std::array<double, 2> SlicePlane::ToPixel(double u, double v) const {
  return {(u - u_lo) / (u_hi - u_lo) * width, (v_hi - v) / (v_hi - v_lo) * height};
}

absl::StatusOr<SlicePlane> MakeSlicePlane(const Volume& volume, int axis, double position,
                                          int panel_size) {
  if (axis < 0 || axis > 2) {
    return absl::InvalidArgumentError(absl::StrCat("--axis: expected x, y or z, got ", axis));
  }
  if (panel_size < 8) {
    return absl::InvalidArgumentError(
        absl::StrCat("--panel-size: must be at least 8 pixels, got ", panel_size));
  }
  // The world bounding box of the sampled region: for an oblique grid the plane spans the whole
  // rotated parallelepiped, and pixels outside it are the renderer's background.
  Vec3 index_lo, index_hi;
  for (int a = 0; a < 3; ++a) {
    index_lo[a] = static_cast<double>(volume.lo()[a]);
    index_hi[a] = static_cast<double>(volume.hi()[a] - 1);
  }
  const std::array<Vec3, 2> box = WorldBounds(volume.grid(), index_lo, index_hi);
  const Vec3& lo = box[0];
  const Vec3& hi = box[1];
  // An oblique grid's box edge is a rounded product (32 - 4e-15 where the user reads 32), so a
  // position typed from `info` or from the range below must not be refused at the edge: within
  // a billionth of the coordinates' size it is the edge. Beyond, the range is printed with
  // enough digits to tell it from the position.
  const double slack =
      1e-9 * std::max({std::abs(lo[axis]), std::abs(hi[axis]), hi[axis] - lo[axis], 1e-300});
  if (!(position >= lo[axis] - slack && position <= hi[axis] + slack)) {
    return absl::InvalidArgumentError(
        absl::StrFormat("--position: %.10g mm is outside the volume's %s range [%.10g, %.10g] mm",
                        position, kAxisNames[axis], lo[axis], hi[axis]));
  }
  SlicePlane plane;
  plane.axis = axis;
  plane.position = std::clamp(position, lo[axis], hi[axis]);
  plane.u_axis = axis == 0 ? 1 : 0;
  plane.v_axis = axis == 2 ? 1 : 2;
  plane.u_lo = lo[plane.u_axis];
  plane.u_hi = hi[plane.u_axis];
  plane.v_lo = lo[plane.v_axis];
  plane.v_hi = hi[plane.v_axis];
  const double u_extent = plane.u_hi - plane.u_lo;
  const double v_extent = plane.v_hi - plane.v_lo;
  // The longer side gets panel_size pixels; the other keeps the aspect ratio (square pixels),
  // at least one pixel.
  const double pixels_per_unit = panel_size / std::max(u_extent, v_extent);
  plane.width = std::max(1, static_cast<int>(std::lround(u_extent * pixels_per_unit)));
  plane.height = std::max(1, static_cast<int>(std::lround(v_extent * pixels_per_unit)));
  return plane;
}

}  // namespace tetrefine::render
