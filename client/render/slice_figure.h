#pragma once

#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "client/render/slice_sampling.h"

namespace tetrefine::render {

// One row of the figure: a mesh on the plane (the paper's Figures 15-16 side by side).
struct FigureRow {
  std::string title;     // e.g. "before: cube.vtu, 1782 tets"
  SliceSamples samples;  // all rows share one plane (same width and height)
};

struct FigureOptions {
  std::string title;  // first line of the figure, e.g. "t1.nii, plane z = 8 mm"
  // Colour range of the two value panels (volume and mesh), volume value units; lo < hi.
  double value_lo = 0.0, value_hi = 1.0;
  // Discrepancy shown at the top of its colour bar (brighter is clamped); > 0.
  double discrepancy_max = 0.1;
  // Draw the tet-plane sections' outlines over the mesh and discrepancy panels.
  bool draw_edges = true;
};

struct PixelRect {
  int x = 0, y = 0, width = 0, height = 0;  // top-left corner and size, pixels
};

// Where everything goes. Per row, left to right: the volume's trilinear values, the mesh's
// linear interpolation, the colour bar of both, the discrepancy, its colour bar. Panels are
// drawn pixel for pixel (no scaling), so panel pixel (c, r) of SliceSamples is figure pixel
// (x + c, y + r). A colour bar is at least kMinColourBarHeight high (its three labels), and a
// row as high as its bars.
inline constexpr int kMinColourBarHeight = 52;
struct FigureLayout {
  struct Row {
    PixelRect volume, mesh, value_bar, discrepancy, discrepancy_bar;
  };
  int width = 0, height = 0;
  std::vector<Row> rows;
};
FigureLayout LayoutFigure(int rows, int panel_width, int panel_height);

// The colour bar's top for a largest discrepancy of `max_discrepancy`: rounded up to 1, 1.5, 2,
// 2.5, 3, 4, 5, 6 or 8 times a power of ten (round numbers, at most half again the maximum, so
// the brightest pixels stay bright), and at least 0.01. The floor keeps a mesh that is exact to
// rounding (1e-16) black instead of stretching its noise over the whole map; 1% of the value range
// is where the eye starts to see a difference.
double DiscrepancyScale(double max_discrepancy);

// A colour bar's label for `value` on a bar from `lo` to `hi`: six significant digits, and 0
// for a value below a billionth of the bar's largest magnitude (an outside review found a
// float32 volume's 0.5th percentile, a denormal 1.96e-44, printed as "1.96182e-44" over the
// next panel).
std::string BarLabel(double value, double lo, double hi);

// The figure as PNG bytes (RGB, 8 bits per channel), drawn with Cairo. Errors: no rows, rows on
// different planes, a bad option, or Cairo failing.
absl::StatusOr<std::string> RenderSliceFigurePng(const std::vector<FigureRow>& rows,
                                                 const FigureOptions& options);

}  // namespace tetrefine::render
