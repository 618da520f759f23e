// tetrefine plot: the convergence of one or more refinements (the JSON of refine --stats-json)
// as a picture: the largest edge-midpoint error and the tets per iteration, side by side.

#include <algorithm>
#include <cstdio>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "absl/strings/ascii.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "client/cli/command_support.h"
#include "client/cli/commands.h"
#include "client/cli/convergence_stats.h"
#include "client/cli/exit_codes.h"
#include "client/cli/file_kind.h"
#include "client/io/file_bytes.h"
#include "client/render/convergence_plot.h"

namespace tetrefine::cli {
namespace {

struct PlotSettings {
  std::vector<std::string> stats_paths;
  std::vector<std::string> labels;  // at most one per stats file; the rest take the default
  std::string output_path;
  int width = 960;
  // --height, or 400 and one legend line more for each run after the third, so that a legend
  // of many runs does not squeeze the panels (an outside review's eleven runs left the error
  // panel 110 pixels).
  int height = 0;
};

int DefaultHeight(size_t runs) {
  return 400 + render::kLegendLineHeight * static_cast<int>(std::max<size_t>(runs, 3) - 3);
}

absl::Status SettingsFromArgs(const ParsedArgs& args, PlotSettings* s) {
  s->stats_paths = args.GetAll("stats-json");
  s->labels = args.GetAll("label");
  if (s->labels.size() > s->stats_paths.size()) {
    return absl::InvalidArgumentError(absl::StrCat("--label: ", s->labels.size(), " labels for ",
                                                   s->stats_paths.size(), " --stats-json files"));
  }
  if (auto text = args.Get("width")) {
    absl::StatusOr<int64_t> n = ParseInteger("width", *text, 200, 8192);
    if (!n.ok()) return n.status();
    s->width = static_cast<int>(*n);
  }
  if (auto text = args.Get("height")) {
    absl::StatusOr<int64_t> n = ParseInteger("height", *text, 150, 8192);
    if (!n.ok()) return n.status();
    s->height = static_cast<int>(*n);
  } else {
    s->height = DefaultHeight(s->stats_paths.size());
  }
  s->output_path = *args.Get("output");
  if (absl::AsciiStrToLower(PathExtension(s->output_path)) != ".png") {
    return absl::InvalidArgumentError(absl::StrCat(s->output_path, ": --output takes a .png file"));
  }
  return CheckOutputPath(s->output_path, "--output", /*mesh=*/false);
}

std::string FileName(const std::string& path) {
  const size_t slash = path.find_last_of('/');
  return slash == std::string::npos ? path : path.substr(slash + 1);
}

// What ran: the scheme, "certified" for a --certify run that was (certified_max_error set),
// "certify, not certified" for one that stopped first (both found by outside reviews: the first
// labelled as the default's, the second as certified), or "" when the file does not say.
std::string Method(const ConvergenceRun& run) {
  if (run.scheme.empty()) return "";
  if (!run.certify) return run.scheme;
  return absl::StrCat(run.scheme, run.certified ? ", certified" : ", certify, not certified");
}

// The run's name in the legend: --label, else its method (with the file name when another run
// has the same method), else the file name.
std::vector<std::string> Names(const PlotSettings& s, const std::vector<ConvergenceRun>& runs) {
  std::map<std::string, int> method_count;
  for (const ConvergenceRun& run : runs) ++method_count[Method(run)];
  std::vector<std::string> names;
  for (size_t i = 0; i < runs.size(); ++i) {
    const std::string method = Method(runs[i]);
    if (i < s.labels.size()) {
      names.push_back(s.labels[i]);
    } else if (method.empty()) {
      names.push_back(FileName(s.stats_paths[i]));
    } else if (method_count[method] > 1) {
      names.push_back(absl::StrCat(method, " (", FileName(s.stats_paths[i]), ")"));
    } else {
      names.push_back(method);
    }
  }
  return names;
}

// Whether every run's errors are relative to the same norm (all given the same --norm-coeff,
// or none given one).
bool OneNorm(const std::vector<ConvergenceRun>& runs) {
  return std::all_of(runs.begin(), runs.end(), [&](const ConvergenceRun& run) {
    return run.norm_coeff == runs.front().norm_coeff;
  });
}

// The error axis's title: relative to the value range, to the one norm every run was given, or
// to each run's own (said in the legend: RelativeTo).
std::string ErrorAxis(const std::vector<ConvergenceRun>& runs) {
  if (!OneNorm(runs)) {
    return "largest edge-midpoint error (relative to each run's norm, in the legend)";
  }
  const std::optional<double> norm = runs.front().norm_coeff;
  if (!norm.has_value()) return "largest edge-midpoint error (relative to the value range)";
  return absl::StrFormat("largest edge-midpoint error (relative to --norm-coeff %g)", *norm);
}

// ", errors relative to X" for a run given --norm-coeff X when the runs' norms differ
// (one_norm false; the axis names a shared one).
std::string RelativeTo(const ConvergenceRun& run, bool one_norm) {
  if (one_norm) return "";
  return run.norm_coeff.has_value() ? absl::StrFormat(", errors relative to %g", *run.norm_coeff)
                                    : ", errors relative to the value range";
}

std::string ErrorText(const ConvergenceRun& run) {
  // No error at all: a run cancelled before its first iteration.
  if (run.max_error.empty()) return "unknown";
  return run.max_error.size() == run.tets.size()
             ? absl::StrFormat("%.4g -> %.4g", run.max_error.front(), run.max_error.back())
             : absl::StrFormat("%.4g -> ?", run.max_error.front());
}

}  // namespace

const CommandSpec& PlotSpec() {
  static const CommandSpec spec{
      .name = "plot",
      .summary =
          "Convergence plot of refine --stats-json files: error and tets per iteration (PNG)",
      .usage =
          "tetrefine plot --stats-json A.json [--stats-json B.json ...] [--label NAME ...]\n"
          "                      --output FIG.png [--width W] [--height H]",
      .description =
          "Draws, side by side, per iteration of each run: the largest edge-midpoint error\n"
          "(relative to the volume's value range, or to the run's --norm-coeff, which the axis\n"
          "or the legend then names; log scale) with a dashed line at epsilon, and\n"
          "the number of tets (log scale). Iteration 0 is the input mesh; the error of the mesh\n"
          "after iteration k is the one measured at the start of iteration k + 1, and the last\n"
          "mesh's is the file's final_max_error; an error of 0 is a triangle on the bottom edge.\n"
          "One coloured line with markers per file; the legend gives its label (--label in\n"
          "order, else the file's scheme, \"certified\" after it with --certify, else its\n"
          "name), why it stopped, its iterations and its tets; past ten files the lines\n"
          "are dashed, then dotted. Runs at different epsilons have each epsilon's line in\n"
          "the colour of its run.",
      .flags =
          {
              {"stats-json", "FILE", "JSON written by tetrefine refine --stats-json", true,
               /*repeated=*/true},
              {"label", "NAME", "legend name of the n-th --stats-json (default: its scheme)", false,
               /*repeated=*/true},
              {"output", "FILE", "the picture, .png", true},
              {"width", "W", "picture width in pixels (default 960)"},
              {"height", "H",
               "picture height in pixels (default 400, 16 more per run after the third)"},
          },
      .positional = ""};
  return spec;
}

int RunPlot(const std::vector<std::string>& args) {
  int exit_code = kExitOk;
  std::optional<ParsedArgs> parsed = ParseCommandLine(PlotSpec(), args, &exit_code);
  if (!parsed.has_value()) return exit_code;
  PlotSettings s;
  if (absl::Status status = SettingsFromArgs(*parsed, &s); !status.ok()) {
    return Fail(status, kExitUsage);
  }
  std::vector<ConvergenceRun> runs;
  for (const std::string& path : s.stats_paths) {
    absl::StatusOr<ConvergenceRun> run = ReadConvergenceRun(path);
    if (!run.ok()) return Fail(run.status(), kExitUsage);
    runs.push_back(*std::move(run));
  }
  const std::vector<std::string> names = Names(s, runs);
  std::vector<render::ConvergenceSeries> series;
  render::ConvergenceOptions options;
  options.width = s.width;
  options.height = s.height;
  options.title = "Convergence: largest edge-midpoint error and tets per iteration";
  options.error_axis = ErrorAxis(runs);
  const bool one_norm = OneNorm(runs);
  for (size_t i = 0; i < runs.size(); ++i) {
    const ConvergenceRun& run = runs[i];
    render::ConvergenceSeries one;
    one.label = absl::StrCat(
        names[i], ": ", run.stop_reason.empty() ? "stop reason unknown" : run.stop_reason, ", ",
        run.tets.size() - 1, run.tets.size() == 2 ? " iteration, " : " iterations, ",
        run.tets.front(), " -> ", run.tets.back(), " tets, epsilon ", run.epsilon,
        RelativeTo(run, one_norm));
    one.error = run.max_error;
    one.tets.assign(run.tets.begin(), run.tets.end());
    series.push_back(std::move(one));
    options.epsilons.push_back(run.epsilon);
  }
  absl::StatusOr<std::string> png = render::RenderConvergencePlotPng(series, options);
  if (!png.ok()) {
    // The only input-dependent failure is a picture too small for the panels and legend.
    const int code = absl::IsInvalidArgument(png.status()) ? kExitUsage : kExitFailed;
    return Fail(absl::StrCat(s.output_path, ": ", png.status().message(), " (--width, --height)"),
                code);
  }
  if (absl::Status written = io::WriteFileAtomically(s.output_path, *png); !written.ok()) {
    return Fail(written, kExitUsage);
  }
  for (size_t i = 0; i < runs.size(); ++i) {
    // The legend's name and the path, the file named once (the legend adds it to a method two
    // runs share).
    const std::string name =
        i < s.labels.size() || Method(runs[i]).empty() ? names[i] : Method(runs[i]);
    std::printf("%s (%s): %zu iterations, tets %lld -> %lld, max edge-midpoint error %s, %s\n",
                name.c_str(), s.stats_paths[i].c_str(), runs[i].tets.size() - 1,
                static_cast<long long>(runs[i].tets.front()),
                static_cast<long long>(runs[i].tets.back()), ErrorText(runs[i]).c_str(),
                runs[i].stop_reason.empty() ? "stop reason unknown" : runs[i].stop_reason.c_str());
  }
  std::printf("Wrote %s: %d x %d pixels, %zu run%s\n", s.output_path.c_str(), s.width, s.height,
              runs.size(), runs.size() == 1 ? "" : "s");
  return kExitOk;
}

}  // namespace tetrefine::cli
