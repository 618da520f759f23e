#pragma once

#include <array>

#include "absl/status/statusor.h"
#include "core/volume.h"

namespace tetrefine::render {

// An axis-aligned plane through a volume, {p : p[axis] = position}, and the pixel grid a figure
// shows of it: the volume's sampled box on the plane, square pixels in world units.
//
// In-plane axes: the horizontal axis u grows to the right, the vertical axis v grows upwards
// (row 0 is the top, at v_hi), as a radiologist's slice viewer draws them:
//   axis z: u = x, v = y;   axis y: u = x, v = z;   axis x: u = y, v = z.
struct SlicePlane {
  int axis = 2;                                           // normal axis: 0 = x, 1 = y, 2 = z
  double position = 0.0;                                  // world coordinate along `axis`
  int u_axis = 0;                                         // world axis drawn horizontally
  int v_axis = 1;                                         // world axis drawn vertically
  double u_lo = 0.0, u_hi = 1.0, v_lo = 0.0, v_hi = 1.0;  // world extent of the panel
  int width = 1, height = 1;                              // pixels, >= 1

  // World point at the centre of pixel (column, row), 0 <= column < width, 0 <= row < height.
  Vec3 PixelCentre(int column, int row) const;
  // Continuous pixel coordinates of in-plane world point (u, v): pixel (c, r) covers
  // [c, c + 1) x [r, r + 1), so a pixel centre maps to (c + 0.5, r + 0.5).
  std::array<double, 2> ToPixel(double u, double v) const;
};

// The plane of `volume` at `position` along `axis` (0, 1, 2), drawn `panel_size` pixels along
// its longer in-plane side (>= 8). Errors name the flag the CLI takes them from: --axis out of
// range, --position outside the volume's sampled range on that axis, --panel-size too small.
absl::StatusOr<SlicePlane> MakeSlicePlane(const Volume& volume, int axis, double position,
                                          int panel_size);

}  // namespace tetrefine::render
