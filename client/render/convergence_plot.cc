#include "client/render/convergence_plot.h"

#include <cairo.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <memory>
#include <numbers>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/strings/str_replace.h"

namespace tetrefine::render {
namespace {

constexpr int kMargin = 12;
constexpr int kTitle = 22;        // the picture's title line
constexpr int kPanelTitle = 18;   // a panel's title line, above it
constexpr int kYAxisTitle = 16;   // the rotated y-axis title, left of the tick labels
constexpr int kYTickLabels = 56;  // room for the y tick labels, left of a panel
constexpr int kXLabels = 36;      // x tick labels and the x-axis title, under a panel
constexpr int kGap = 28;          // between the two panels (besides the right one's y labels)
constexpr int kLegendPad = 8;     // between the x-axis title and the legend
constexpr int kMinPanelWidth = 100;
constexpr int kMinPanelHeight = 80;
constexpr double kFontSize = 11.0;
constexpr double kMarkerRadius = 3.5;

struct SurfaceDeleter {
  void operator()(cairo_surface_t* s) const { cairo_surface_destroy(s); }
};
struct ContextDeleter {
  void operator()(cairo_t* c) const { cairo_destroy(c); }
};
using Surface = std::unique_ptr<cairo_surface_t, SurfaceDeleter>;
using Context = std::unique_ptr<cairo_t, ContextDeleter>;

bool Plottable(double v) { return std::isfinite(v) && v > 0.0; }
// Drawn, on the bottom edge when 0: a run whose error vanished must not look like one that
// stopped (until 2026-11-25 its line just ended).
bool Drawable(double v) { return Plottable(v) || v == 0.0; }

// The whole decades around the plottable `values`: [floor(log10 min), ceil(log10 max)], at least
// one decade; [0, 1] when there are none.
std::array<double, 2> DecadeRange(const std::vector<double>& values) {
  double lo = std::numeric_limits<double>::infinity();
  double hi = -lo;
  for (double v : values) {
    if (!Plottable(v)) continue;
    lo = std::min(lo, v);
    hi = std::max(hi, v);
  }
  if (!(lo <= hi)) return {0.0, 1.0};
  // The tolerance keeps an exact power of ten (1000) from opening a decade of its own.
  const double lo_decade = std::floor(std::log10(lo) + 1e-9);
  double hi_decade = std::ceil(std::log10(hi) - 1e-9);
  if (hi_decade <= lo_decade) hi_decade = lo_decade + 1.0;
  return {lo_decade, hi_decade};
}

void SetColour(cairo_t* cr, const Rgb& c) {
  cairo_set_source_rgb(cr, c.r / 255.0, c.g / 255.0, c.b / 255.0);
}

double TextWidth(cairo_t* cr, const std::string& text) {
  cairo_text_extents_t extents;
  cairo_text_extents(cr, text.c_str(), &extents);
  return extents.x_advance;
}

// `align` 0: left at x; 0.5: centred on x; 1: right at x. y is the baseline.
void Text(cairo_t* cr, double x, double y, const std::string& text, double align = 0.0) {
  cairo_move_to(cr, x - align * TextWidth(cr, text), y);
  cairo_show_text(cr, text.c_str());
}

// 2000, 0.05, 1e-05 -> "1e-5", 1e+06 -> "1e6".
std::string TickLabel(double value) {
  return absl::StrReplaceAll(absl::StrFormat("%g", value),
                             {{"e+0", "e"}, {"e+", "e"}, {"e-0", "e-"}});
}

// Iteration ticks: every one up to 12 iterations, else a round step giving at most 12.
double XTickStep(double x_max) {
  for (double step : {1.0, 2.0, 5.0, 10.0, 20.0, 50.0, 100.0, 200.0, 500.0}) {
    if (x_max / step <= 12.0) return step;
  }
  return std::ceil(x_max / 12.0);
}

void DrawAxes(cairo_t* cr, const PlotArea& area, const std::string& title,
              const std::string& y_title) {
  const PixelRect& r = area.rect;
  cairo_save(cr);
  cairo_set_line_width(cr, 1.0);
  // Decades: a light grid line and a labelled tick; 2..9 times a decade: a short tick (labelled
  // too, at 2 and 5, when the axis spans at most two decades).
  const int decades = static_cast<int>(std::lround(area.log_hi - area.log_lo));
  const int label_step = std::max(1, static_cast<int>(std::ceil(decades / 8.0)));
  for (int d = 0; d <= decades; ++d) {
    const double decade = std::pow(10.0, area.log_lo + d);
    const double y = area.Row(decade) + 0.5;
    cairo_set_source_rgb(cr, 0.88, 0.88, 0.88);
    cairo_move_to(cr, r.x, y);
    cairo_line_to(cr, r.x + r.width, y);
    cairo_stroke(cr);
    cairo_set_source_rgb(cr, 0.3, 0.3, 0.3);
    cairo_move_to(cr, r.x - 6, y);
    cairo_line_to(cr, r.x, y);
    cairo_stroke(cr);
    if (d % label_step == 0) Text(cr, r.x - 8, y + 4, TickLabel(decade), 1.0);
    if (d == decades) break;
    for (int m = 2; m <= 9; ++m) {
      const double ym = area.Row(m * decade) + 0.5;
      cairo_move_to(cr, r.x - 3, ym);
      cairo_line_to(cr, r.x, ym);
      cairo_stroke(cr);
      if (decades <= 2 && (m == 2 || m == 5)) Text(cr, r.x - 8, ym + 4, TickLabel(m * decade), 1.0);
    }
  }
  if (area.zero_row) {  // the row of 0, under a gap that says the scale breaks there
    const double y = std::floor(area.ZeroY()) + 0.5;
    cairo_move_to(cr, r.x - 6, y);
    cairo_line_to(cr, r.x, y);
    cairo_stroke(cr);
    Text(cr, r.x - 8, y + 4, "0", 1.0);
    const double gap = std::floor(area.ZeroY() - kZeroBand / 2.0) + 0.5;
    cairo_move_to(cr, r.x - 5, gap + 2);
    cairo_line_to(cr, r.x + 5, gap - 2);
    cairo_stroke(cr);
  }
  const double step = XTickStep(area.x_max);
  for (double i = 0; i <= area.x_max + 1e-9; i += step) {
    const double x = std::floor(area.X(i)) + 0.5;
    cairo_set_source_rgb(cr, 0.93, 0.93, 0.93);
    cairo_move_to(cr, x, r.y);
    cairo_line_to(cr, x, r.y + r.height);
    cairo_stroke(cr);
    cairo_set_source_rgb(cr, 0.3, 0.3, 0.3);
    cairo_move_to(cr, x, r.y + r.height);
    cairo_line_to(cr, x, r.y + r.height + 5);
    cairo_stroke(cr);
    Text(cr, x, r.y + r.height + 17, absl::StrFormat("%g", i), 0.5);
  }
  cairo_set_source_rgb(cr, 0.4, 0.4, 0.4);
  cairo_rectangle(cr, r.x - 0.5, r.y - 0.5, r.width + 1.0, r.height + 1.0);
  cairo_stroke(cr);
  cairo_set_source_rgb(cr, 0, 0, 0);
  Text(cr, r.x + r.width / 2.0, r.y + r.height + kXLabels - 4, "iteration", 0.5);
  Text(cr, r.x, r.y - 6, title);
  cairo_save(cr);
  cairo_translate(cr, r.x - kYTickLabels - 4, r.y + r.height / 2.0);
  cairo_rotate(cr, -std::numbers::pi / 2);
  Text(cr, 0, 0, y_title, 0.5);
  cairo_restore(cr);
  cairo_restore(cr);
}

void Marker(cairo_t* cr, double x, double y) {
  cairo_new_sub_path(cr);
  cairo_arc(cr, x, y, kMarkerRadius, 0, 2 * std::numbers::pi);
  cairo_fill(cr);
}

// A zero value: a triangle pointing down, its tip on the bottom edge's row.
void ZeroMarker(cairo_t* cr, double x, double y) {
  const double s = kMarkerRadius * 1.6;
  cairo_new_sub_path(cr);
  cairo_move_to(cr, x, y + s * 0.5);
  cairo_line_to(cr, x - s, y - s * 1.2);
  cairo_line_to(cr, x + s, y - s * 1.2);
  cairo_close_path(cr);
  cairo_fill(cr);
}

// The series' line through its plottable points (broken where one is not) and its markers.
void DrawSeries(cairo_t* cr, const PlotArea& area, const std::vector<double>& values,
                const Rgb& colour, const std::vector<double>& dash) {
  const PixelRect& r = area.rect;
  cairo_save(cr);
  cairo_rectangle(cr, r.x, r.y, r.width, r.height);
  cairo_clip(cr);
  SetColour(cr, colour);
  cairo_set_line_width(cr, 2.0);
  cairo_set_line_join(cr, CAIRO_LINE_JOIN_ROUND);
  cairo_set_dash(cr, dash.data(), static_cast<int>(dash.size()), 0.0);
  bool drawing = false;
  const auto y_of = [&](double v) { return v == 0.0 ? area.ZeroY() : area.Y(v); };
  for (size_t i = 0; i < values.size(); ++i) {
    if (!Drawable(values[i])) {
      drawing = false;
      continue;
    }
    const double x = area.X(static_cast<double>(i));
    const double y = y_of(values[i]);
    if (drawing) {
      cairo_line_to(cr, x, y);
    } else {
      cairo_move_to(cr, x, y);
      drawing = true;
    }
  }
  cairo_stroke(cr);
  cairo_set_dash(cr, nullptr, 0, 0.0);
  for (size_t i = 0; i < values.size(); ++i) {
    const double x = area.X(static_cast<double>(i));
    if (Plottable(values[i])) Marker(cr, x, area.Y(values[i]));
    if (values[i] == 0.0) ZeroMarker(cr, x, area.ZeroY());
  }
  cairo_restore(cr);
}

// The dashed line at `epsilon`.
void DrawEpsilon(cairo_t* cr, const PlotArea& area, double epsilon, const Rgb& colour) {
  const PixelRect& r = area.rect;
  const double y = area.Row(epsilon) + 0.5;
  cairo_save(cr);
  SetColour(cr, colour);
  cairo_set_line_width(cr, 1.0);
  const std::array<double, 2> dash = {6.0, 4.0};
  cairo_set_dash(cr, dash.data(), static_cast<int>(dash.size()), 0.0);
  cairo_move_to(cr, r.x, y);
  cairo_line_to(cr, r.x + r.width, y);
  cairo_stroke(cr);
  cairo_restore(cr);
}

// Its label, baseline at label_y: at the left, where the errors of the first iterations are
// usually well above epsilon (at the right the runs end at it), on white, after every epsilon
// line, so that no other epsilon's line crosses it.
void DrawEpsilonLabel(cairo_t* cr, const PlotArea& area, double epsilon, const Rgb& colour,
                      double label_y) {
  const PixelRect& r = area.rect;
  const std::string label = absl::StrFormat("epsilon = %g", epsilon);
  cairo_save(cr);
  cairo_set_source_rgb(cr, 1, 1, 1);
  cairo_rectangle(cr, r.x + 3, label_y - kFontSize, TextWidth(cr, label) + 2, kFontSize + 3);
  cairo_fill(cr);
  SetColour(cr, colour);
  Text(cr, r.x + 4, label_y, label);
  cairo_restore(cr);
}

}  // namespace

double PlotArea::X(double iteration) const {
  const double span = rect.width - 2.0 * kPlotInset;
  return rect.x + kPlotInset + iteration / x_max * span;
}

double PlotArea::Y(double value) const {
  const double span = rect.height - 2.0 * kPlotInset - (zero_row ? kZeroBand : 0);
  return rect.y + kPlotInset + (log_hi - std::log10(value)) / (log_hi - log_lo) * span;
}

double PlotArea::ZeroY() const { return rect.y + rect.height - kPlotInset; }

int PlotArea::Row(double value) const {
  const int row = static_cast<int>(std::floor(Y(value)));
  return std::clamp(row, rect.y, rect.y + rect.height - 1);
}

absl::StatusOr<ConvergenceLayout> LayoutConvergencePlot(
    const std::vector<ConvergenceSeries>& series, const ConvergenceOptions& options) {
  if (series.empty()) return absl::InvalidArgumentError("a convergence plot needs a run");
  const int n = static_cast<int>(series.size());
  const int left = kYAxisTitle + kYTickLabels;
  const int top = kMargin + kTitle + kPanelTitle;
  const int bottom = kXLabels + kLegendPad + n * kLegendLineHeight + kMargin;
  const int panel_width = (options.width - 2 * kMargin - 2 * left - kGap) / 2;
  const int panel_height = options.height - top - bottom;
  if (panel_width < kMinPanelWidth) {
    return absl::InvalidArgumentError(
        absl::StrCat("width ", options.width, " is too small: the two panels need at least ",
                     2 * kMargin + 2 * left + kGap + 2 * kMinPanelWidth, " pixels"));
  }
  if (panel_height < kMinPanelHeight) {
    return absl::InvalidArgumentError(absl::StrCat(
        "height ", options.height, " is too small: the panels and a legend of ", n,
        n == 1 ? " run" : " runs", " need at least ", top + bottom + kMinPanelHeight, " pixels"));
  }
  ConvergenceLayout layout;
  layout.width = options.width;
  layout.height = options.height;
  layout.error.rect = {kMargin + left, top, panel_width, panel_height};
  layout.tets.rect = {kMargin + left + panel_width + kGap + left, top, panel_width, panel_height};
  layout.legend = {kMargin + left, top + panel_height + kXLabels + kLegendPad,
                   options.width - 2 * kMargin - left, n * kLegendLineHeight};
  std::vector<double> errors = options.epsilons;
  std::vector<double> tets;
  size_t points = 0;
  for (const ConvergenceSeries& s : series) {
    errors.insert(errors.end(), s.error.begin(), s.error.end());
    tets.insert(tets.end(), s.tets.begin(), s.tets.end());
    points = std::max({points, s.error.size(), s.tets.size()});
  }
  const double x_max = points > 2 ? static_cast<double>(points - 1) : 1.0;
  const std::array<double, 2> error_range = DecadeRange(errors);
  const std::array<double, 2> tets_range = DecadeRange(tets);
  for (PlotArea* area : {&layout.error, &layout.tets}) area->x_max = x_max;
  for (const ConvergenceSeries& s : series) {
    layout.error.zero_row |= std::find(s.error.begin(), s.error.end(), 0.0) != s.error.end();
    layout.tets.zero_row |= std::find(s.tets.begin(), s.tets.end(), 0.0) != s.tets.end();
  }
  layout.error.log_lo = error_range[0];
  layout.error.log_hi = error_range[1];
  layout.tets.log_lo = tets_range[0];
  layout.tets.log_hi = tets_range[1];
  return layout;
}

Rgb SeriesColour(size_t i) {
  // Matplotlib's "tab10" cycle: distinguishable, and none is black, white or grey but the 8th,
  // which is a mid grey (127) no axis or grid line uses.
  static constexpr std::array<Rgb, 10> kCycle = {{{31, 119, 180},
                                                  {255, 127, 14},
                                                  {44, 160, 44},
                                                  {214, 39, 40},
                                                  {148, 103, 189},
                                                  {140, 86, 75},
                                                  {227, 119, 194},
                                                  {127, 127, 127},
                                                  {188, 189, 34},
                                                  {23, 190, 207}}};
  return kCycle[i % kCycle.size()];
}

std::vector<double> SeriesDash(size_t i) {
  switch (i / 10 % 4) {
    case 1:
      return {8.0, 4.0};
    case 2:
      return {2.0, 3.0};
    case 3:
      return {8.0, 3.0, 2.0, 3.0};
    default:
      return {};
  }
}

std::vector<double> SeparateLabels(const std::vector<double>& wanted, double spacing) {
  std::vector<size_t> order(wanted.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::stable_sort(order.begin(), order.end(),
                   [&](size_t a, size_t b) { return wanted[a] < wanted[b]; });
  std::vector<double> placed(wanted.size());
  double last = -std::numeric_limits<double>::infinity();
  for (size_t i : order) {
    placed[i] = std::max(wanted[i], last + spacing);
    last = placed[i];
  }
  return placed;
}

absl::StatusOr<std::string> RenderConvergencePlotPng(const std::vector<ConvergenceSeries>& series,
                                                     const ConvergenceOptions& options) {
  absl::StatusOr<ConvergenceLayout> layout = LayoutConvergencePlot(series, options);
  if (!layout.ok()) return layout.status();
  Surface figure(cairo_image_surface_create(CAIRO_FORMAT_RGB24, layout->width, layout->height));
  Context cr(cairo_create(figure.get()));
  cairo_set_source_rgb(cr.get(), 1, 1, 1);
  cairo_paint(cr.get());
  cairo_select_font_face(cr.get(), "sans-serif", CAIRO_FONT_SLANT_NORMAL, CAIRO_FONT_WEIGHT_NORMAL);
  cairo_set_source_rgb(cr.get(), 0, 0, 0);
  cairo_set_font_size(cr.get(), kFontSize + 2);
  Text(cr.get(), kMargin, kMargin + kFontSize + 2, options.title);
  cairo_set_font_size(cr.get(), kFontSize);

  DrawAxes(cr.get(), layout->error, options.error_axis, "max error");
  DrawAxes(cr.get(), layout->tets, "tets", "tets");
  // Each epsilon once, with the first series that has it.
  std::vector<double> epsilons;
  std::vector<size_t> first_series;
  for (size_t i = 0; i < options.epsilons.size(); ++i) {
    const double e = options.epsilons[i];
    if (Plottable(e) && std::find(epsilons.begin(), epsilons.end(), e) == epsilons.end()) {
      epsilons.push_back(e);
      first_series.push_back(i);
    }
  }
  std::vector<double> label_rows;
  for (double e : epsilons) label_rows.push_back(layout->error.Row(e) + 0.5 - 4.0);
  label_rows = SeparateLabels(label_rows, kFontSize + 2.0);
  const auto epsilon_colour = [&](size_t k) {
    return epsilons.size() == 1 ? kEpsilonColour : SeriesColour(first_series[k]);
  };
  for (size_t k = 0; k < epsilons.size(); ++k) {
    DrawEpsilon(cr.get(), layout->error, epsilons[k], epsilon_colour(k));
  }
  for (size_t k = 0; k < epsilons.size(); ++k) {
    DrawEpsilonLabel(cr.get(), layout->error, epsilons[k], epsilon_colour(k), label_rows[k]);
  }
  for (size_t i = 0; i < series.size(); ++i) {
    DrawSeries(cr.get(), layout->error, series[i].error, SeriesColour(i), SeriesDash(i));
    DrawSeries(cr.get(), layout->tets, series[i].tets, SeriesColour(i), SeriesDash(i));
  }
  const PixelRect& legend = layout->legend;
  for (size_t i = 0; i < series.size(); ++i) {
    const double y =
        legend.y + static_cast<double>(i) * kLegendLineHeight + kLegendLineHeight / 2.0;
    SetColour(cr.get(), SeriesColour(i));
    cairo_set_line_width(cr.get(), 2.0);
    const std::vector<double> dash = SeriesDash(i);
    cairo_set_dash(cr.get(), dash.data(), static_cast<int>(dash.size()), 0.0);
    cairo_move_to(cr.get(), legend.x, y);
    cairo_line_to(cr.get(), legend.x + 24, y);
    cairo_stroke(cr.get());
    cairo_set_dash(cr.get(), nullptr, 0, 0.0);
    Marker(cr.get(), legend.x + 12, y);
    cairo_set_source_rgb(cr.get(), 0, 0, 0);
    Text(cr.get(), legend.x + 32, y + 4, series[i].label);
  }
  cairo_surface_flush(figure.get());
  if (cairo_status(cr.get()) != CAIRO_STATUS_SUCCESS) {
    return absl::InternalError(
        absl::StrCat("drawing the plot: ", cairo_status_to_string(cairo_status(cr.get()))));
  }
  std::string png;
  const cairo_status_t status = cairo_surface_write_to_png_stream(
      figure.get(),
      [](void* closure, const unsigned char* data, unsigned int length) {
        static_cast<std::string*>(closure)->append(reinterpret_cast<const char*>(data), length);
        return CAIRO_STATUS_SUCCESS;
      },
      &png);
  if (status != CAIRO_STATUS_SUCCESS) {
    return absl::InternalError(absl::StrCat("encoding the PNG: ", cairo_status_to_string(status)));
  }
  return png;
}

}  // namespace tetrefine::render
