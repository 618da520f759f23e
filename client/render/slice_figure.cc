#include "client/render/slice_figure.h"

#include <cairo.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <memory>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "client/render/colormap.h"

namespace tetrefine::render {
namespace {

constexpr int kMargin = 12;
constexpr int kHeader = 24;      // the figure title line
constexpr int kRowTitle = 18;    // a row's title line
constexpr int kPanelTitle = 16;  // a panel's title line
constexpr int kGap = 10;         // between panels
constexpr int kRowGap = 12;      // between rows
constexpr int kBarWidth = 14;
constexpr int kBarLabels = 60;  // room for the numbers right of a colour bar
constexpr double kFontSize = 11.0;

struct SurfaceDeleter {
  void operator()(cairo_surface_t* s) const { cairo_surface_destroy(s); }
};
struct ContextDeleter {
  void operator()(cairo_t* c) const { cairo_destroy(c); }
};
using Surface = std::unique_ptr<cairo_surface_t, SurfaceDeleter>;
using Context = std::unique_ptr<cairo_t, ContextDeleter>;

double Normalized(double value, double lo, double hi) {
  if (std::isnan(value)) return value;
  return hi > lo ? (value - lo) / (hi - lo) : 0.5;
}

// A width x height RGB image whose pixel i is colour(values[i]).
template <typename Colour>
Surface PanelImage(const std::vector<double>& values, int width, int height, Colour colour) {
  Surface image(cairo_image_surface_create(CAIRO_FORMAT_RGB24, width, height));
  cairo_surface_flush(image.get());
  unsigned char* data = cairo_image_surface_get_data(image.get());
  const int stride = cairo_image_surface_get_stride(image.get());
  for (int row = 0; row < height; ++row) {
    auto* line = reinterpret_cast<uint32_t*>(data + static_cast<ptrdiff_t>(row) * stride);
    for (int column = 0; column < width; ++column) {
      const Rgb c = colour(values[static_cast<size_t>(row) * width + column]);
      line[column] = (uint32_t{c.r} << 16) | (uint32_t{c.g} << 8) | uint32_t{c.b};
    }
  }
  cairo_surface_mark_dirty(image.get());
  return image;
}

void Paint(cairo_t* cr, cairo_surface_t* image, const PixelRect& at) {
  cairo_save(cr);
  cairo_set_source_surface(cr, image, at.x, at.y);
  cairo_pattern_set_filter(cairo_get_source(cr), CAIRO_FILTER_NEAREST);
  cairo_rectangle(cr, at.x, at.y, at.width, at.height);
  cairo_fill(cr);
  cairo_restore(cr);
}

// A one-pixel grey frame just outside the panel, so its extent shows where no tet covers it
// (white on white); the panel's own pixels are untouched.
void Frame(cairo_t* cr, const PixelRect& at) {
  cairo_save(cr);
  cairo_set_source_rgb(cr, 0.75, 0.75, 0.75);
  cairo_set_line_width(cr, 1.0);
  cairo_rectangle(cr, at.x - 0.5, at.y - 0.5, at.width + 1.0, at.height + 1.0);
  cairo_stroke(cr);
  cairo_restore(cr);
}

void Text(cairo_t* cr, double x, double y, const std::string& text) {
  cairo_move_to(cr, x, y);
  cairo_show_text(cr, text.c_str());
}

// The sides of every tet section, clipped to the panel.
void DrawSections(cairo_t* cr, const SliceSamples& s, const PixelRect& at, double r, double g,
                  double b, double alpha) {
  cairo_save(cr);
  cairo_rectangle(cr, at.x, at.y, at.width, at.height);
  cairo_clip(cr);
  cairo_set_source_rgba(cr, r, g, b, alpha);
  cairo_set_line_width(cr, 0.7);
  for (const TetSection& section : s.sections) {
    for (size_t i = 0; i < section.corners.size(); ++i) {
      const auto [px, py] = s.plane.ToPixel(section.corners[i][0], section.corners[i][1]);
      if (i == 0) {
        cairo_move_to(cr, at.x + px, at.y + py);
      } else {
        cairo_line_to(cr, at.x + px, at.y + py);
      }
    }
    if (section.corners.size() > 2) cairo_close_path(cr);
  }
  cairo_stroke(cr);
  cairo_restore(cr);
}

// A vertical colour bar, `hi` at the top, with three labels.
template <typename Colour>
void DrawBar(cairo_t* cr, const PixelRect& at, Colour colour, double lo, double hi) {
  std::vector<double> ramp(static_cast<size_t>(at.height) * at.width);
  for (int row = 0; row < at.height; ++row) {
    const double t = at.height > 1 ? 1.0 - static_cast<double>(row) / (at.height - 1) : 1.0;
    std::fill_n(ramp.begin() + static_cast<ptrdiff_t>(row) * at.width, at.width, t);
  }
  Surface image = PanelImage(ramp, at.width, at.height, colour);
  Paint(cr, image.get(), at);
  cairo_set_source_rgb(cr, 0, 0, 0);
  const double x = at.x + at.width + 4;
  Text(cr, x, at.y + kFontSize - 1, BarLabel(hi, lo, hi));
  Text(cr, x, at.y + at.height / 2.0 + kFontSize / 2 - 1, BarLabel((lo + hi) / 2, lo, hi));
  Text(cr, x, at.y + at.height, BarLabel(lo, lo, hi));
}

}  // namespace

std::string BarLabel(double value, double lo, double hi) {
  const double scale = std::max(std::abs(lo), std::abs(hi));
  if (std::abs(value) <= 1e-9 * scale) return "0";
  return absl::StrFormat("%.6g", value);
}

FigureLayout LayoutFigure(int rows, int panel_width, int panel_height) {
  FigureLayout layout;
  // A colour bar is at least kMinColourBarHeight high whatever the panels: a thin plane (an outside
  // review cut a 100 x 100 x 2 volume along x: panels 3 pixels high) printed its bars' three
  // labels over each other.
  const int bar_height = std::max(panel_height, kMinColourBarHeight);
  const int row_height = kRowTitle + kPanelTitle + bar_height;
  for (int r = 0; r < rows; ++r) {
    const int y = kMargin + kHeader + r * (row_height + kRowGap) + kRowTitle + kPanelTitle;
    FigureLayout::Row row;
    int x = kMargin;
    row.volume = {x, y, panel_width, panel_height};
    x += panel_width + kGap;
    row.mesh = {x, y, panel_width, panel_height};
    x += panel_width + kGap;
    row.value_bar = {x, y, kBarWidth, bar_height};
    x += kBarWidth + kBarLabels;
    row.discrepancy = {x, y, panel_width, panel_height};
    x += panel_width + kGap;
    row.discrepancy_bar = {x, y, kBarWidth, bar_height};
    layout.width = x + kBarWidth + kBarLabels + kMargin;
    layout.rows.push_back(row);
  }
  layout.height = kMargin + kHeader + rows * row_height + (rows - 1) * kRowGap + kMargin;
  return layout;
}

double DiscrepancyScale(double max_discrepancy) {
  constexpr double kFloor = 0.01;
  if (!(max_discrepancy > kFloor)) return kFloor;
  const double decade = std::pow(10.0, std::floor(std::log10(max_discrepancy)));
  for (double step : {1.0, 1.5, 2.0, 2.5, 3.0, 4.0, 5.0, 6.0, 8.0, 10.0}) {
    if (max_discrepancy <= step * decade * (1 + 1e-12)) return step * decade;
  }
  return 10.0 * decade;
}

absl::StatusOr<std::string> RenderSliceFigurePng(const std::vector<FigureRow>& rows,
                                                 const FigureOptions& options) {
  if (rows.empty()) return absl::InvalidArgumentError("a figure needs at least one mesh");
  const SlicePlane& plane = rows[0].samples.plane;
  for (const FigureRow& row : rows) {
    if (row.samples.plane.width != plane.width || row.samples.plane.height != plane.height) {
      return absl::InvalidArgumentError("every row of a figure must show the same plane");
    }
  }
  if (!(options.value_hi >= options.value_lo) || !(options.discrepancy_max > 0.0)) {
    return absl::InvalidArgumentError(absl::StrCat("bad colour ranges: values [", options.value_lo,
                                                   ", ", options.value_hi, "], discrepancy max ",
                                                   options.discrepancy_max));
  }
  const FigureLayout layout =
      LayoutFigure(static_cast<int>(rows.size()), plane.width, plane.height);
  Surface figure(cairo_image_surface_create(CAIRO_FORMAT_RGB24, layout.width, layout.height));
  Context cr(cairo_create(figure.get()));
  cairo_set_source_rgb(cr.get(), 1, 1, 1);
  cairo_paint(cr.get());
  cairo_select_font_face(cr.get(), "sans-serif", CAIRO_FONT_SLANT_NORMAL, CAIRO_FONT_WEIGHT_NORMAL);
  cairo_set_font_size(cr.get(), kFontSize);
  cairo_set_source_rgb(cr.get(), 0, 0, 0);
  cairo_set_font_size(cr.get(), kFontSize + 2);
  Text(cr.get(), kMargin, kMargin + kFontSize + 2, options.title);
  cairo_set_font_size(cr.get(), kFontSize);

  const auto value_colour = [&](double v) {
    return ValueColour(Normalized(v, options.value_lo, options.value_hi));
  };
  const auto discrepancy_colour = [&](double d) {
    return DiscrepancyColour(std::isnan(d) ? d : d / options.discrepancy_max);
  };
  for (size_t r = 0; r < rows.size(); ++r) {
    const SliceSamples& s = rows[r].samples;
    const FigureLayout::Row& at = layout.rows[r];
    cairo_set_source_rgb(cr.get(), 0, 0, 0);
    cairo_set_font_size(cr.get(), kFontSize + 1);
    Text(cr.get(), at.volume.x, at.volume.y - kPanelTitle - 5, rows[r].title);
    cairo_set_font_size(cr.get(), kFontSize);
    Text(cr.get(), at.volume.x, at.volume.y - 4, "volume (trilinear)");
    Text(cr.get(), at.mesh.x, at.mesh.y - 4, "mesh (linear)");
    Text(cr.get(), at.discrepancy.x, at.discrepancy.y - 4,
         absl::StrFormat("|trilinear - linear| / range: max %.3g", s.max_discrepancy));

    for (const PixelRect& panel : {at.volume, at.mesh, at.discrepancy}) Frame(cr.get(), panel);
    Surface volume = PanelImage(s.trilinear, plane.width, plane.height, value_colour);
    Paint(cr.get(), volume.get(), at.volume);
    Surface mesh = PanelImage(s.linear, plane.width, plane.height, value_colour);
    Paint(cr.get(), mesh.get(), at.mesh);
    Surface discrepancy = PanelImage(s.discrepancy, plane.width, plane.height, discrepancy_colour);
    Paint(cr.get(), discrepancy.get(), at.discrepancy);
    if (options.draw_edges) {
      DrawSections(cr.get(), s, at.mesh, 0, 0, 0, 0.6);
      DrawSections(cr.get(), s, at.discrepancy, 0.6, 0.6, 0.6, 0.8);
    }
    DrawBar(
        cr.get(), at.value_bar, [](double t) { return ValueColour(t); }, options.value_lo,
        options.value_hi);
    DrawBar(
        cr.get(), at.discrepancy_bar, [](double t) { return DiscrepancyColour(t); }, 0.0,
        options.discrepancy_max);
  }
  cairo_surface_flush(figure.get());
  if (cairo_status(cr.get()) != CAIRO_STATUS_SUCCESS) {
    return absl::InternalError(
        absl::StrCat("drawing the figure: ", cairo_status_to_string(cairo_status(cr.get()))));
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
