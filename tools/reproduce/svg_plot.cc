#include "tools/reproduce/svg_plot.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "tools/reproduce/schemes.h"

namespace tetrefine::reproduce {
namespace {

constexpr double kWidth = 760, kHeight = 350;
constexpr double kPanelW = 300, kPanelH = 220, kTop = 80;
constexpr double kLeft[2] = {70, 440};
constexpr const char* kColours[] = {"#1f77b4", "#d62728", "#2ca02c", "#9467bd"};

struct Series {
  std::vector<double> y;  // index = iterations applied
};

// Axis mapping of one panel.
struct Panel {
  double left;
  double x_max;  // iterations
  double y_lo, y_hi;
  bool log;
  double X(double x) const { return left + kPanelW * x / std::max(1.0, x_max); }
  double Y(double y) const {
    const double t = log ? (std::log10(y) - y_lo) / (y_hi - y_lo) : (y - y_lo) / (y_hi - y_lo);
    return kTop + kPanelH * (1.0 - t);
  }
};

std::string Polyline(const Panel& p, const std::vector<double>& y, const char* colour,
                     const char* dash) {
  std::string points;
  for (size_t i = 0; i < y.size(); ++i) {
    if (p.log && !(y[i] > 0)) continue;
    absl::StrAppendFormat(&points, "%.1f,%.1f ", p.X(static_cast<double>(i)), p.Y(y[i]));
  }
  return absl::StrFormat(
      "<polyline fill=\"none\" stroke=\"%s\" stroke-width=\"1.8\"%s points=\"%s\"/>\n", colour,
      dash, points);
}

std::string Axes(const Panel& p, const std::string& title, const std::string& y_label) {
  std::string s;
  const double bottom = kTop + kPanelH;
  absl::StrAppendFormat(&s,
                        "<rect x=\"%.1f\" y=\"%.1f\" width=\"%.1f\" height=\"%.1f\" fill=\"none\" "
                        "stroke=\"#444\"/>\n",
                        p.left, kTop, kPanelW, kPanelH);
  absl::StrAppendFormat(&s, "<text x=\"%.1f\" y=\"%.1f\" text-anchor=\"middle\">%s</text>\n",
                        p.left + kPanelW / 2, kTop - 8, title);
  absl::StrAppendFormat(&s,
                        "<text x=\"%.1f\" y=\"%.1f\" text-anchor=\"middle\">iterations</text>\n",
                        p.left + kPanelW / 2, bottom + 34);
  absl::StrAppendFormat(&s,
                        "<text transform=\"translate(%.1f,%.1f) rotate(-90)\" "
                        "text-anchor=\"middle\">%s</text>\n",
                        p.left - 52, kTop + kPanelH / 2, y_label);
  const int step = p.x_max > 10 ? 2 : 1;
  for (int i = 0; i <= static_cast<int>(p.x_max); i += step) {
    absl::StrAppendFormat(&s,
                          "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\" stroke=\"#444\"/>"
                          "<text x=\"%.1f\" y=\"%.1f\" text-anchor=\"middle\">%d</text>\n",
                          p.X(i), bottom, p.X(i), bottom + 5, p.X(i), bottom + 18, i);
  }
  if (p.log) {
    for (int e = static_cast<int>(std::ceil(p.y_lo)); e <= static_cast<int>(p.y_hi); ++e) {
      const double y = p.Y(std::pow(10.0, e));
      absl::StrAppendFormat(&s,
                            "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\" "
                            "stroke=\"#ddd\"/><text x=\"%.1f\" y=\"%.1f\" "
                            "text-anchor=\"end\">1e%d</text>\n",
                            p.left, y, p.left + kPanelW, y, p.left - 6, y + 4, e);
    }
  } else {
    const double range = p.y_hi - p.y_lo;
    const double raw = range / 5;
    const double mag = std::pow(10.0, std::floor(std::log10(raw)));
    const double tick = raw / mag < 2 ? 2 * mag : (raw / mag < 5 ? 5 * mag : 10 * mag);
    for (double v = 0; v <= p.y_hi + 1e-12; v += tick) {
      absl::StrAppendFormat(&s,
                            "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\" "
                            "stroke=\"#ddd\"/><text x=\"%.1f\" y=\"%.1f\" "
                            "text-anchor=\"end\">%g</text>\n",
                            p.left, p.Y(v), p.left + kPanelW, p.Y(v), p.left - 6, p.Y(v) + 4, v);
    }
  }
  return s;
}

}  // namespace

std::string CasePlotSvg(const CaseRecord& c) {
  // The paper scheme's run to convergence of each epsilon.
  const std::vector<const RunRecord*> runs = RunsToConvergence(c, kPaperScheme.name);
  double x_max = 1, err_max = 0, tets_lo = 1e300, tets_hi = 1;
  std::vector<Series> max_err, mean_err, tets;
  for (const RunRecord* r : runs) {
    Series mx, mn, nt;
    nt.y.push_back(static_cast<double>(r->initial_tets));
    for (const IterationStats& s : r->iterations) {
      mx.y.push_back(s.max_error);
      mn.y.push_back(s.mean_error);
      nt.y.push_back(static_cast<double>(s.final_tets));
    }
    mx.y.push_back(r->final_max_error);
    mn.y.push_back(r->final_mean_error);
    x_max = std::max(x_max, static_cast<double>(r->iterations.size()));
    for (double e : mx.y) err_max = std::max(err_max, e);
    for (double t : nt.y) {
      tets_lo = std::min(tets_lo, t);
      tets_hi = std::max(tets_hi, t);
    }
    if (r->uniform_at_max.reached) {
      tets_hi = std::max(tets_hi, static_cast<double>(r->uniform_at_max.tets));
    }
    max_err.push_back(mx);
    mean_err.push_back(mn);
    tets.push_back(nt);
  }
  for (const RunRecord* r : runs) err_max = std::max(err_max, r->epsilon);
  if (tets_lo > tets_hi) tets_lo = 1;
  const Panel left{kLeft[0], x_max, 0.0, err_max * 1.08, false};
  const Panel right{kLeft[1], x_max, std::floor(std::log10(tets_lo)),
                    std::ceil(std::log10(tets_hi) + 1e-9), true};

  std::string s = absl::StrFormat(
      "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"%g\" height=\"%g\" viewBox=\"0 0 %g %g\" "
      "font-family=\"sans-serif\" font-size=\"12\">\n"
      "<rect width=\"100%%\" height=\"100%%\" fill=\"white\"/>\n",
      kWidth, kHeight, kWidth, kHeight);
  absl::StrAppendFormat(&s,
                        "<text x=\"%g\" y=\"20\" text-anchor=\"middle\" font-size=\"14\" "
                        "font-weight=\"bold\">%s: %s, %s</text>\n",
                        kWidth / 2, c.name, c.volume_name, c.mesh_kind);
  s += Axes(left, "edge-midpoint error (max solid, mean dashed)", "relative error");
  s += Axes(right, "tets (uniform 1:8 at equal lattice max: dashed)", "tets");
  std::string legend;
  for (size_t i = 0; i < runs.size(); ++i) {
    const char* colour = kColours[i % 4];
    const double eps = runs[i]->epsilon;
    absl::StrAppendFormat(&s,
                          "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\" stroke=\"%s\" "
                          "stroke-dasharray=\"2,3\"/>\n",
                          left.X(0), left.Y(eps), left.X(x_max), left.Y(eps), colour);
    s += Polyline(left, max_err[i].y, colour, "");
    s += Polyline(left, mean_err[i].y, colour, " stroke-dasharray=\"6,4\"");
    s += Polyline(right, tets[i].y, colour, "");
    if (runs[i]->uniform_at_max.reached) {
      const double y = right.Y(static_cast<double>(runs[i]->uniform_at_max.tets));
      absl::StrAppendFormat(&s,
                            "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\" stroke=\"%s\" "
                            "stroke-dasharray=\"6,4\"/>\n",
                            right.X(0), y, right.X(x_max), y, colour);
    }
    const double lx = 180 + 200 * static_cast<double>(i);
    absl::StrAppendFormat(&legend,
                          "<line x1=\"%.1f\" y1=\"42\" x2=\"%.1f\" y2=\"42\" stroke=\"%s\" "
                          "stroke-width=\"2\"/><text x=\"%.1f\" y=\"46\">epsilon = %g</text>\n",
                          lx, lx + 24, colour, lx + 30, eps);
  }
  s += legend;
  s += "</svg>\n";
  return s;
}

}  // namespace tetrefine::reproduce
