#pragma once

// The convergence plot of `tetrefine plot`: two panels side by side, the largest edge-midpoint
// error per iteration (log y, with a dashed line at epsilon) and the tets per iteration (log y),
// one coloured line with markers per run, and a legend under them.

#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "client/render/colormap.h"
#include "client/render/slice_figure.h"

namespace tetrefine::render {

// One run. Index i of both vectors is iteration i (0 = the input mesh). A value of 0 (an error
// that vanished: a volume the mesh represents exactly) is drawn as a downward triangle on a row
// labelled 0 under the decades; negative or non-finite values have no place on a log axis and
// are left out (the line breaks there).
struct ConvergenceSeries {
  std::string label;          // the legend's text for this run
  std::vector<double> error;  // largest edge-midpoint error of the mesh after iteration i
  std::vector<double> tets;   // tets after iteration i
};

struct ConvergenceOptions {
  int width = 960, height = 400;  // the whole picture, pixels
  std::string title;              // first line of the picture; may be empty
  // A horizontal dashed line on the error panel for each (> 0; duplicates are drawn once),
  // labelled with its value; epsilons[i] is series i's. When they are not all equal each line
  // takes the colour of the first series with that epsilon (black lines could not say whose
  // they are) and the labels are moved apart so that none covers another.
  std::vector<double> epsilons;
  // The error panel's axis title: what the errors are relative to.
  std::string error_axis = "largest edge-midpoint error (relative to the value range)";
};

// One panel's plot area and its axes: x is the iteration, y is log10 of the value.
struct PlotArea {
  PixelRect rect;     // inside the frame; lines and markers are clipped to it
  double x_max = 1;   // iterations 0 .. x_max span the width less kPlotInset on both sides
  double log_lo = 0;  // 10^log_lo at the bottom (less the inset), 10^log_hi at the top; whole
  double log_hi = 1;  // decades, log_hi > log_lo
  // Whether some value is 0: the decades then end kZeroBand pixels higher, and the row of 0
  // (ZeroY) is labelled under them.
  bool zero_row = false;
  double X(double iteration) const;
  double Y(double value) const;  // value > 0
  double ZeroY() const;          // the row of the value 0 (meaningful when zero_row)
  // The pixel row a horizontal line at `value` is drawn on (one pixel wide, not anti-aliased).
  int Row(double value) const;
};
inline constexpr int kPlotInset = 10;
inline constexpr int kZeroBand = 24;

struct ConvergenceLayout {
  int width = 0, height = 0;
  PlotArea error, tets;
  PixelRect legend;  // one line per series
};

// Where everything goes, and the axes' ranges: each y axis spans the whole decades around its
// positive values (and the epsilons, on the error panel); x spans 0 to the last iteration of any
// series (at least 1). Errors: no series, or a picture too small for the panels and legend
// (the message says which size is needed).
absl::StatusOr<ConvergenceLayout> LayoutConvergencePlot(
    const std::vector<ConvergenceSeries>& series, const ConvergenceOptions& options);

// The colour of series i (a ten-colour cycle, distinct from black, white and the greys).
Rgb SeriesColour(size_t i);
// The dash pattern of series i's line (cairo_set_dash lengths, pixels; empty = solid): solid
// for the first ten series, then dashed, dotted and dash-dotted for each further ten, so that
// forty runs differ in colour or line.
std::vector<double> SeriesDash(size_t i);
// The legend's height per series, pixels.
inline constexpr int kLegendLineHeight = 16;
// Baselines for labels wanted at the rows `wanted` (any order), each moved down as little as
// needed so that no two are closer than `spacing`; in the order of `wanted`.
std::vector<double> SeparateLabels(const std::vector<double>& wanted, double spacing);
// The epsilon line's colour (dashed).
inline constexpr Rgb kEpsilonColour{0, 0, 0};

// The picture as PNG bytes (RGB, 8 bits per channel), drawn with Cairo. Errors: those of
// LayoutConvergencePlot, or Cairo failing.
absl::StatusOr<std::string> RenderConvergencePlotPng(const std::vector<ConvergenceSeries>& series,
                                                     const ConvergenceOptions& options);

}  // namespace tetrefine::render
