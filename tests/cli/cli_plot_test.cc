// tetrefine plot: reading refine's --stats-json, the plot's layout, and the command end to end
// (the PNG's size and where its lines are; bad inputs give one line naming them, exit 2, no file).

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <ostream>
#include <set>
#include <string>
#include <tuple>
#include <vector>

#include "absl/strings/match.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_join.h"
#include "client/cli/convergence_stats.h"
#include "client/render/colormap.h"
#include "client/render/convergence_plot.h"
#include "gtest/gtest.h"
#include "tests/cli/cli_test_util.h"
#include "tests/io/io_test_util.h"
#include "tests/render/png_image.h"
#include "tests/support/geometry.h"

namespace tetrefine::clitest {
namespace {

using cli::ConvergenceRun;
using cli::ParseConvergenceRun;
using io::iotest::ReadBytes;
using io::iotest::ScratchDir;
using io::iotest::WriteBytes;
using render::testing::DecodePng;
using render::testing::Image;

struct Iteration {
  int64_t initial_tets, final_tets;
  double max_error;
};

// A stats file shaped like stats_json.cc's (the fields plot reads, and a few it does not).
std::string StatsJson(const std::string& scheme, double epsilon, const std::vector<Iteration>& its,
                      double final_max_error, const std::string& stop_reason) {
  std::vector<std::string> items;
  for (size_t i = 0; i < its.size(); ++i) {
    items.push_back(absl::StrCat(R"({"iteration": )", i + 1, R"(, "initial_tets": )",
                                 its[i].initial_tets, R"(, "final_tets": )", its[i].final_tets,
                                 R"(, "max_error": )", its[i].max_error,
                                 R"(, "mean_error": 0.01, "quality": {"min": 0.2}})"));
  }
  return absl::StrCat(R"({"volume": "v.nii", "options": {"epsilon": )", epsilon,
                      R"(, "max_iterations": 32, "scheme": ")", scheme, R"("}, "iterations": [)",
                      absl::StrJoin(items, ", "), R"(], "stop_reason": ")", stop_reason,
                      R"(", "final_max_error": )", final_max_error, "}\n");
}

// Run A: four meshes 1000 .. 20000 tets, error 0.5 down to 0.05 (below epsilon 0.12).
std::string RunA() {
  return StatsJson("longest-edge", 0.12,
                   {{1000, 3000, 0.5}, {3000, 9000, 0.3}, {9000, 20000, 0.15}}, 0.05, "converged");
}
// Run B: five meshes 1000 .. 7000 tets, error 0.45 down to 0.18 (stops above epsilon).
std::string RunB() {
  return StatsJson("paper", 0.12,
                   {{1000, 2000, 0.45}, {2000, 4000, 0.4}, {4000, 6000, 0.25}, {6000, 7000, 0.2}},
                   0.18, "quality_floor");
}

TEST(CliPlotStats, ReadsTetsAndErrorsPerIterationWithTheInputFirst) {
  absl::StatusOr<ConvergenceRun> run = ParseConvergenceRun(RunA());
  ASSERT_TRUE(run.ok()) << run.status();
  EXPECT_EQ(run->scheme, "longest-edge");
  EXPECT_EQ(run->stop_reason, "converged");
  EXPECT_EQ(run->epsilon, 0.12);
  EXPECT_EQ(run->tets, (std::vector<int64_t>{1000, 3000, 9000, 20000}));
  EXPECT_EQ(run->max_error, (std::vector<double>{0.5, 0.3, 0.15, 0.05}));
}

TEST(CliPlotStats, ACancelledRunHasNoErrorForItsLastMesh) {
  absl::StatusOr<ConvergenceRun> run =
      ParseConvergenceRun(StatsJson("paper", 0.1, {{10, 80, 0.4}}, 0.4, "cancelled"));
  ASSERT_TRUE(run.ok()) << run.status();
  EXPECT_EQ(run->tets, (std::vector<int64_t>{10, 80}));
  EXPECT_EQ(run->max_error, (std::vector<double>{0.4}));
}

TEST(CliPlotStats, ErrorsNameTheField) {
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"", "not valid JSON: parse error at line 1"},
      {"{\"options\": {\"epsilon\": 0.1},\n \"iterations\": [",
       "not valid JSON: parse error at line 2"},
      {"[1, 2]", "expected a JSON object at the top"},
      {R"({"iterations": []})", "options: missing"},
      {R"({"options": {}, "iterations": []})", "options.epsilon: missing"},
      {R"({"options": {"epsilon": null}})", "options.epsilon: expected a number, got null"},
      {R"({"options": {"epsilon": -1}})", "options.epsilon: must be > 0"},
      {R"({"options": {"epsilon": 0.1, "scheme": 3}})", "options.scheme: expected a string"},
      {R"({"options": {"epsilon": 0.1}})", "iterations: missing"},
      {R"({"options": {"epsilon": 0.1}, "iterations": {}})", "iterations: expected an array"},
      {R"({"options": {"epsilon": 0.1}, "iterations": []})", "input: missing"},
      {R"({"options": {"epsilon": 0.1}, "iterations": [], "input": {"tets": -3}})",
       "input.tets: expected a whole number >= 0, got -3"},
      {R"({"options": {"epsilon": 0.1}, "iterations": [3]})", "iterations[0]: expected an object"},
      {R"({"options": {"epsilon": 0.1}, "iterations": [{"final_tets": 8, "max_error": 1}]})",
       "iterations[0].initial_tets: missing"},
      {R"({"options": {"epsilon": 0.1}, "iterations": [{"initial_tets": 1, "final_tets": 8,
          "max_error": 1}, {"final_tets": 2.5, "max_error": 1}]})",
       "iterations[1].final_tets: expected a whole number >= 0, got 2.5"},
      {R"({"options": {"epsilon": 0.1}, "iterations": [{"initial_tets": 1, "final_tets": 8,
          "max_error": null}]})",
       "iterations[0].max_error: expected a number, got null"},
      // Fields that contradict each other, as no run of refine writes them (an outside review
      // plotted an error of -1 as a silent gap, and reversed iterations as "29291 -> 5175").
      {R"({"options": {"epsilon": 0.1}, "iterations": [{"initial_tets": 1, "final_tets": 8,
          "max_error": -1}]})",
       "iterations[0].max_error: must be >= 0, got -1"},
      {R"({"options": {"epsilon": 0.1}, "iterations": [{"initial_tets": 1, "final_tets": 8,
          "max_error": 0.5}], "final_max_error": -0.5})",
       "final_max_error: must be >= 0, got -0.5"},
      {R"({"options": {"epsilon": 0.1}, "iterations": [{"iteration": 2, "initial_tets": 8,
          "final_tets": 20, "max_error": 0.3}, {"iteration": 1, "initial_tets": 1,
          "final_tets": 8, "max_error": 0.5}]})",
       "iterations[0].iteration: expected 1 (iterations in order), got 2"},
      {R"({"options": {"epsilon": 0.1}, "iterations": [{"initial_tets": 1, "final_tets": 8,
          "max_error": 0.5}, {"initial_tets": 9, "final_tets": 20, "max_error": 0.3}]})",
       "iterations[1].initial_tets: 9 is not the 8 tets the iteration before ended with"},
      {R"({"options": {"epsilon": 0.1}, "iterations": [{"initial_tets": 1, "final_tets": 8,
          "max_error": 0.5}], "output_mesh": {"tets": 29}})",
       "output_mesh.tets: 29 is not the 8 tets the last iteration ended with"},
      {R"({"options": {"epsilon": 0.1}, "iterations": [], "input": {"tets": 1782},
          "output_mesh": {"tets": 29547}})",
       "output_mesh.tets: 29547 is not the 1782 tets of the input (no iteration ran)"},
      {R"({"options": {"epsilon": 0.1, "certify": "yes"}, "iterations": []})",
       "options.certify: expected true or false, got \"yes\""},
      {R"({"options": {"epsilon": 0.1, "norm_coeff": 0}, "iterations": []})",
       "options.norm_coeff: expected a number > 0 or null, got 0"},
      {R"({"options": {"epsilon": 0.1}, "input": {"tets": 1782}, "iterations": [{
          "initial_tets": 1000, "final_tets": 8, "max_error": 0.5}]})",
       "iterations[0].initial_tets: 1000 is not the input's 1782 tets"},
      {R"({"options": {"epsilon": 0.1}, "iterations": [{"initial_tets": 1, "final_tets": 8,
          "max_error": 0.5, "mean_error": -0.1}]})",
       "iterations[0].mean_error: must be >= 0, got -0.1"},
      {R"({"options": {"epsilon": 0.1}, "iterations": [], "input": {"tets": 5},
          "final_mean_error": -1})",
       "final_mean_error: must be >= 0, got -1"},
      {R"({"options": {"epsilon": 0.1}, "iterations": [], "input": {"tets": 5},
          "stop_reason": "banana"})",
       "stop_reason: \"banana\" is not one refine writes"},
      {R"({"options": {"epsilon": 0.1}, "iterations": [], "input": {"tets": 5},
          "certified_max_error": 0.05})",
       "certified_max_error: set, but options.certify is not true"},
      {R"({"options": {"epsilon": 0.1, "norm_coeff": 5000}, "norm_coeff": 31003,
          "iterations": [], "input": {"tets": 5}})",
       "norm_coeff: 31003 is not options.norm_coeff 5000"},
  };
  for (const auto& [json, expected] : cases) {
    absl::StatusOr<ConvergenceRun> run = ParseConvergenceRun(json);
    ASSERT_FALSE(run.ok()) << json;
    EXPECT_TRUE(absl::StrContains(run.status().message(), expected))
        << "'" << run.status().message() << "' should contain '" << expected << "'";
    EXPECT_EQ(run.status().message().find('\n'), std::string::npos) << run.status().message();
  }
}

// What the legend and the error axis say: a certified run is named so (it was labelled as the
// default scheme's), and errors relative to a --norm-coeff say so on the axis, or in the legend
// when the runs differ (they were drawn on the value range's axis without a word).
TEST(CliPlot, TheLegendAndAxisSayCertifiedAndTheNormCoefficient) {
  ScratchDir dir;
  std::string certified = RunA();
  certified.replace(certified.find(R"("scheme": ")"), 0, R"("certify": true, )");
  // A certify run that stopped before it was certified has certified_max_error null.
  std::string uncertified = certified;
  certified.replace(certified.find(R"("final_max_error")"), 0, R"("certified_max_error": 0.1, )");
  WriteBytes(dir.File("u.json"), uncertified);
  std::string normed = RunA();
  normed.replace(normed.find(R"("scheme": ")"), 0, R"("norm_coeff": 3000, )");
  WriteBytes(dir.File("a.json"), RunA());
  WriteBytes(dir.File("c.json"), certified);
  WriteBytes(dir.File("n.json"), normed);
  absl::StatusOr<ConvergenceRun> run = ParseConvergenceRun(certified);
  ASSERT_TRUE(run.ok()) << run.status();
  EXPECT_TRUE(run->certify);
  EXPECT_TRUE(run->certified);
  EXPECT_FALSE(run->norm_coeff.has_value());
  run = ParseConvergenceRun(normed);
  ASSERT_TRUE(run.ok()) << run.status();
  EXPECT_EQ(run->norm_coeff, 3000.0);

  const ProcessResult two =
      RunTetrefine({"plot", "--stats-json", dir.File("a.json"), "--stats-json", dir.File("c.json"),
                    "--stats-json", dir.File("u.json"), "--output", dir.File("two.png")});
  ASSERT_EQ(two.exit_code, 0) << two.err;
  EXPECT_TRUE(absl::StrContains(two.out, "longest-edge (" + dir.File("a.json") + "): 3 iterations"))
      << two.out;
  EXPECT_TRUE(absl::StrContains(
      two.out, "longest-edge, certified (" + dir.File("c.json") + "): 3 iterations"))
      << two.out;
  EXPECT_TRUE(absl::StrContains(
      two.out, "longest-edge, certify, not certified (" + dir.File("u.json") + "): 3 iterations"))
      << two.out;
  // Two of one method: the legend tells them apart by file, stdout names each file once.
  const ProcessResult same =
      RunTetrefine({"plot", "--stats-json", dir.File("a.json"), "--stats-json", dir.File("a.json"),
                    "--output", dir.File("same.png")});
  ASSERT_EQ(same.exit_code, 0) << same.err;
  EXPECT_FALSE(absl::StrContains(same.out, "(a.json) (")) << same.out;
  EXPECT_TRUE(absl::StrContains(same.out, "longest-edge (" + dir.File("a.json") + "): "))
      << same.out;
  // The axis title is drawn, not printed: the picture of runs relative to another norm differs
  // from the same runs relative to the value range only in the words of the title.
  const ProcessResult range =
      RunTetrefine({"plot", "--stats-json", dir.File("a.json"), "--output", dir.File("r.png")});
  const ProcessResult norm =
      RunTetrefine({"plot", "--stats-json", dir.File("n.json"), "--output", dir.File("n.png")});
  ASSERT_EQ(range.exit_code, 0) << range.err;
  ASSERT_EQ(norm.exit_code, 0) << norm.err;
  EXPECT_NE(ReadBytes(dir.File("r.png")), ReadBytes(dir.File("n.png")));
}

std::vector<render::ConvergenceSeries> SeriesAB() {
  return {{"A", {0.5, 0.3, 0.15, 0.05}, {1000, 3000, 9000, 20000}},
          {"B", {0.45, 0.4, 0.25, 0.2, 0.18}, {1000, 2000, 4000, 6000, 7000}}};
}

TEST(CliPlotLayout, AxesSpanTheWholeDecadesAroundTheDataAndEpsilon) {
  render::ConvergenceOptions options;
  options.width = 800;
  options.height = 360;
  options.epsilons = {0.12};
  absl::StatusOr<render::ConvergenceLayout> layout =
      render::LayoutConvergencePlot(SeriesAB(), options);
  ASSERT_TRUE(layout.ok()) << layout.status();
  EXPECT_EQ(layout->width, 800);
  EXPECT_EQ(layout->height, 360);
  EXPECT_EQ(layout->error.x_max, 4.0);
  EXPECT_EQ(layout->error.log_lo, -2.0);  // 0.05
  EXPECT_EQ(layout->error.log_hi, 0.0);   // 0.5
  EXPECT_EQ(layout->tets.log_lo, 3.0);    // 1000 is its own decade's bottom
  EXPECT_EQ(layout->tets.log_hi, 5.0);    // 20000
  // Side by side, inside the picture, the legend under both.
  EXPECT_LT(layout->error.rect.x + layout->error.rect.width, layout->tets.rect.x);
  EXPECT_LE(layout->tets.rect.x + layout->tets.rect.width, 800);
  EXPECT_GT(layout->legend.y, layout->error.rect.y + layout->error.rect.height);
  EXPECT_LE(layout->legend.y + layout->legend.height, 360);
  // Up is more; the first and last iterations sit kPlotInset inside the frame.
  EXPECT_LT(layout->tets.Y(20000), layout->tets.Y(1000));
  EXPECT_DOUBLE_EQ(layout->tets.Y(100000), layout->tets.rect.y + render::kPlotInset);
  EXPECT_DOUBLE_EQ(layout->error.X(0), layout->error.rect.x + render::kPlotInset);
  EXPECT_DOUBLE_EQ(layout->error.X(4),
                   layout->error.rect.x + layout->error.rect.width - render::kPlotInset);

  options.height = 150;
  absl::StatusOr<render::ConvergenceLayout> small =
      render::LayoutConvergencePlot(SeriesAB(), options);
  ASSERT_FALSE(small.ok());
  EXPECT_TRUE(absl::StrContains(small.status().message(), "height 150 is too small"));
}

int CountColour(const Image& image, const render::PixelRect& r, const render::Rgb& colour) {
  int n = 0;
  for (int y = r.y; y < r.y + r.height; ++y) {
    for (int x = r.x; x < r.x + r.width; ++x) n += image.At(x, y) == colour;
  }
  return n;
}

// Of the row's pixels inside `r` (less the inset), how many have `colour`.
double RowShare(const Image& image, const render::PixelRect& r, int row,
                const render::Rgb& colour) {
  const render::PixelRect line{r.x + render::kPlotInset, row, r.width - 2 * render::kPlotInset, 1};
  return static_cast<double>(CountColour(image, line, colour)) / line.width;
}

TEST(CliPlot, TwoRunsMakeTwoPanelsWithTheirLinesAndTheEpsilonLine) {
  ScratchDir dir;
  WriteBytes(dir.File("a.json"), RunA());
  WriteBytes(dir.File("b.json"), RunB());
  const ProcessResult run = RunTetrefine(
      {"plot", "--stats-json", dir.File("a.json"), "--stats-json", dir.File("b.json"), "--label",
       "run A", "--output", dir.File("c.png"), "--width", "800", "--height", "360"});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_EQ(run.err, "");
  EXPECT_TRUE(absl::StrContains(
      run.out, absl::StrCat("Wrote ", dir.File("c.png"), ": 800 x 360 pixels, 2 runs")))
      << run.out;
  EXPECT_TRUE(absl::StrContains(
      run.out, "run A (" + dir.File("a.json") +
                   "): 3 iterations, tets 1000 -> 20000, max edge-midpoint error 0.5 -> 0.05, "
                   "converged"))
      << run.out;
  // The second run has no --label: its scheme names it.
  EXPECT_TRUE(absl::StrContains(run.out, "paper (" + dir.File("b.json") + "): 4 iterations"))
      << run.out;
  absl::StatusOr<Image> image = DecodePng(ReadBytes(dir.File("c.png")));
  ASSERT_TRUE(image.ok()) << image.status();
  ASSERT_EQ(image->width, 800);
  ASSERT_EQ(image->height, 360);

  render::ConvergenceOptions options;
  options.width = 800;
  options.height = 360;
  options.epsilons = {0.12, 0.12};
  absl::StatusOr<render::ConvergenceLayout> layout =
      render::LayoutConvergencePlot(SeriesAB(), options);
  ASSERT_TRUE(layout.ok()) << layout.status();
  const render::PlotArea& error = layout->error;
  const render::PlotArea& tets = layout->tets;

  // Epsilon: a dashed line across the error panel on its row, and not on the rows below.
  const int eps_row = error.Row(0.12);
  const double on_line = RowShare(*image, error.rect, eps_row, render::kEpsilonColour);
  EXPECT_GT(on_line, 0.4) << "row " << eps_row;
  EXPECT_LT(on_line, 0.9) << "the line should be dashed";
  for (int off : {3, 6}) {
    EXPECT_LT(RowShare(*image, error.rect, eps_row + off, render::kEpsilonColour), 0.05) << off;
  }
  EXPECT_LT(RowShare(*image, tets.rect, tets.Row(0.12 * 1e5), render::kEpsilonColour), 0.05)
      << "no epsilon line on the tets panel";

  // Each run's colour in both panels and in the legend; no third colour.
  for (size_t s = 0; s < 2; ++s) {
    const render::Rgb colour = render::SeriesColour(s);
    EXPECT_GT(CountColour(*image, error.rect, colour), 40) << "series " << s;
    EXPECT_GT(CountColour(*image, tets.rect, colour), 40) << "series " << s;
    EXPECT_GT(CountColour(*image, layout->legend, colour), 20) << "series " << s;
  }
  EXPECT_EQ(CountColour(*image, {0, 0, 800, 360}, render::SeriesColour(2)), 0);

  // Markers where the data put them: their centre pixel has the run's colour.
  const auto centre = [&](const render::PlotArea& area, double iteration, double value) {
    return image->At(static_cast<int>(std::floor(area.X(iteration))),
                     static_cast<int>(std::floor(area.Y(value))));
  };
  EXPECT_EQ(centre(tets, 3, 20000), render::SeriesColour(0));
  EXPECT_EQ(centre(tets, 4, 7000), render::SeriesColour(1));
  EXPECT_EQ(centre(error, 3, 0.05), render::SeriesColour(0));
  EXPECT_EQ(centre(error, 4, 0.18), render::SeriesColour(1));
  // Run A has no iteration 4: nothing of its colour there.
  EXPECT_NE(centre(tets, 4, 20000), render::SeriesColour(0));
}

// Runs at different epsilons (an outside review compared 0.08, 0.1 and 0.12 on the demo): each
// epsilon's line is in its run's colour, not black, so the plot says whose line it is.
TEST(CliPlot, EpsilonLinesOfDifferentEpsilonsTakeTheirRunsColours) {
  ScratchDir dir;
  const std::vector<double> epsilons = {0.08, 0.1, 0.12};
  std::vector<std::string> args = {"plot"};
  for (size_t k = 0; k < epsilons.size(); ++k) {
    const std::string path = dir.File(absl::StrCat("r", k, ".json"));
    WriteBytes(path, StatsJson("longest-edge", epsilons[k],
                               {{1000, 3000, 0.5}, {3000, 9000, 0.3}, {9000, 20000, 0.15}}, 0.05,
                               "converged"));
    args.insert(args.end(), {"--stats-json", path});
  }
  args.insert(args.end(), {"--output", dir.File("c.png"), "--width", "800", "--height", "400"});
  const ProcessResult run = RunTetrefine(args);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  absl::StatusOr<Image> image = DecodePng(ReadBytes(dir.File("c.png")));
  ASSERT_TRUE(image.ok()) << image.status();
  std::vector<render::ConvergenceSeries> series(3);
  for (render::ConvergenceSeries& one : series) {
    one.error = {0.5, 0.3, 0.15, 0.05};
    one.tets = {1000, 3000, 9000, 20000};
  }
  render::ConvergenceOptions options;
  options.width = 800;
  options.height = 400;
  options.epsilons = epsilons;
  absl::StatusOr<render::ConvergenceLayout> layout = render::LayoutConvergencePlot(series, options);
  ASSERT_TRUE(layout.ok()) << layout.status();
  for (size_t k = 0; k < epsilons.size(); ++k) {
    const int row = layout->error.Row(epsilons[k]);
    EXPECT_GT(RowShare(*image, layout->error.rect, row, render::SeriesColour(k)), 0.3)
        << "epsilon " << epsilons[k] << " row " << row;
    EXPECT_LT(RowShare(*image, layout->error.rect, row, render::kEpsilonColour), 0.05)
        << "epsilon " << epsilons[k] << " drawn black";
  }
}

// Labels moved apart: none closer than the spacing, none above where it was wanted, each as
// close to it as the ones above allow; random rows, many seeds.
TEST(CliPlotLayout, SeparatedLabelsKeepTheirSpacingAndMoveAsLittleAsNeeded) {
  for (uint64_t seed : testing::Seeds(50)) {
    uint64_t state = seed * 6364136223846793005ull + 1442695040888963407ull;
    const auto next = [&] {
      state = state * 6364136223846793005ull + 1442695040888963407ull;
      return static_cast<double>(state >> 40) / static_cast<double>(1ull << 24);
    };
    std::vector<double> wanted(1 + static_cast<size_t>(next() * 8));
    for (double& w : wanted) w = 100.0 * next();
    const double spacing = 13.0;
    const std::vector<double> placed = render::SeparateLabels(wanted, spacing);
    ASSERT_EQ(placed.size(), wanted.size());
    std::vector<size_t> order(wanted.size());
    for (size_t i = 0; i < order.size(); ++i) order[i] = i;
    std::stable_sort(order.begin(), order.end(),
                     [&](size_t a, size_t b) { return wanted[a] < wanted[b]; });
    for (size_t k = 0; k < order.size(); ++k) {
      const size_t i = order[k];
      EXPECT_GE(placed[i], wanted[i]) << "seed " << seed;
      if (k == 0) {
        EXPECT_EQ(placed[i], wanted[i]) << "seed " << seed;
      } else {
        const double above = placed[order[k - 1]];
        EXPECT_GE(placed[i] - above, spacing - 1e-9) << "seed " << seed;
        EXPECT_EQ(placed[i], std::max(wanted[i], above + spacing)) << "seed " << seed;
      }
    }
  }
}

// Forty runs differ in colour or line: ten colours, then a dashed, a dotted and a dash-dotted
// round of them (an outside review's eleventh run was the first's blue line).
TEST(CliPlotLayout, FortySeriesDifferInColourOrDash) {
  std::set<std::tuple<int, int, int, std::vector<double>>> styles;
  for (size_t i = 0; i < 40; ++i) {
    const render::Rgb c = render::SeriesColour(i);
    styles.insert({c.r, c.g, c.b, render::SeriesDash(i)});
    if (i < 10) {
      EXPECT_TRUE(render::SeriesDash(i).empty()) << i;
    }
  }
  EXPECT_EQ(styles.size(), 40u);
}

// Without --height the picture grows by a legend line for each run after the third, so the
// panels keep their size; --height is kept as given.
TEST(CliPlot, TheDefaultHeightGrowsWithTheLegend) {
  ScratchDir dir;
  for (int runs : {1, 3, 11}) {
    std::vector<std::string> args = {"plot"};
    for (int k = 0; k < runs; ++k) {
      const std::string path = dir.File(absl::StrCat("r", k, ".json"));
      WriteBytes(path, RunA());
      args.insert(args.end(), {"--stats-json", path});
    }
    args.insert(args.end(), {"--output", dir.File("c.png")});
    const ProcessResult run = RunTetrefine(args);
    ASSERT_EQ(run.exit_code, 0) << run.err;
    absl::StatusOr<Image> image = DecodePng(ReadBytes(dir.File("c.png")));
    ASSERT_TRUE(image.ok()) << image.status();
    EXPECT_EQ(image->height, 400 + render::kLegendLineHeight * std::max(0, runs - 3)) << runs;
    EXPECT_TRUE(absl::StrContains(run.out, absl::StrCat("x ", image->height, " pixels")))
        << run.out;
  }
}

// refine of the 40-tet grid in the bump volume at `epsilon`, its --stats-json in dir/s.json.
void RefineWithStats(const ScratchDir& dir, const std::string& epsilon) {
  WriteVolume(dir.File("v.nii"), BumpVolume({9, 9, 9}, {0, 0, 0}, {1, 1, 1}));
  WriteMeshFile(dir.File("m.vtu"), testing::FiveTetMesh({1, 1, 1}, {7, 7, 7}, {2, 2, 2}));
  const ProcessResult refine = RunTetrefine(
      {"refine", "--volume", dir.File("v.nii"), "--mesh", dir.File("m.vtu"), "--epsilon", epsilon,
       "--output", dir.File("r.vtu"), "--stats-json", dir.File("s.json"), "--quiet"});
  ASSERT_EQ(refine.exit_code, 0) << refine.err;
}

TEST(CliPlot, ReadsWhatRefineWritesAtTheDefaultSize) {
  ScratchDir dir;
  RefineWithStats(dir, "0.05");
  const ProcessResult run =
      RunTetrefine({"plot", "--stats-json", dir.File("s.json"), "--output", dir.File("c.png")});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_TRUE(absl::StrContains(run.out, "longest-edge (" + dir.File("s.json") + "): ")) << run.out;
  EXPECT_TRUE(absl::StrContains(run.out, "tets 40 -> ")) << run.out;
  absl::StatusOr<Image> image = DecodePng(ReadBytes(dir.File("c.png")));
  ASSERT_TRUE(image.ok()) << image.status();
  EXPECT_EQ(image->width, 960);
  EXPECT_EQ(image->height, 400);
  absl::StatusOr<ConvergenceRun> stats = cli::ReadConvergenceRun(dir.File("s.json"));
  ASSERT_TRUE(stats.ok()) << stats.status();
  ASSERT_GE(stats->tets.size(), 3u) << "the test volume should need several iterations";
  EXPECT_EQ(stats->max_error.size(), stats->tets.size());
  EXPECT_LE(stats->max_error.back(), 0.05);  // converged
}

// A run that met epsilon before its first iteration (epsilon 10 is above any relative error):
// one point, at iteration 0, in both panels; a cancelled one has no error.
TEST(CliPlot, ARunWithNoIterationIsOnePoint) {
  ScratchDir dir;
  RefineWithStats(dir, "10");
  absl::StatusOr<ConvergenceRun> stats = cli::ReadConvergenceRun(dir.File("s.json"));
  ASSERT_TRUE(stats.ok()) << stats.status();
  EXPECT_EQ(stats->tets, (std::vector<int64_t>{40}));
  ASSERT_EQ(stats->max_error.size(), 1u);
  EXPECT_GT(stats->max_error[0], 0.0);
  EXPECT_EQ(stats->stop_reason, "converged");

  const ProcessResult run = RunTetrefine({"plot", "--stats-json", dir.File("s.json"), "--output",
                                          dir.File("c.png"), "--width", "800", "--height", "360"});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_TRUE(absl::StrContains(run.out, "): 0 iterations, tets 40 -> 40, ")) << run.out;
  absl::StatusOr<Image> image = DecodePng(ReadBytes(dir.File("c.png")));
  ASSERT_TRUE(image.ok()) << image.status();
  render::ConvergenceOptions options;
  options.width = 800;
  options.height = 360;
  options.epsilons = {10.0};
  const std::vector<render::ConvergenceSeries> series = {{"", stats->max_error, {40}}};
  absl::StatusOr<render::ConvergenceLayout> layout = render::LayoutConvergencePlot(series, options);
  ASSERT_TRUE(layout.ok()) << layout.status();
  EXPECT_EQ(image->At(static_cast<int>(std::floor(layout->tets.X(0))),
                      static_cast<int>(std::floor(layout->tets.Y(40)))),
            render::SeriesColour(0));

  WriteBytes(dir.File("cancelled.json"),
             R"({"options": {"epsilon": 0.1}, "input": {"tets": 7}, "iterations": [],
                 "stop_reason": "cancelled", "final_max_error": 0.3})");
  const ProcessResult cancelled = RunTetrefine(
      {"plot", "--stats-json", dir.File("cancelled.json"), "--output", dir.File("d.png")});
  ASSERT_EQ(cancelled.exit_code, 0) << cancelled.err;
  EXPECT_TRUE(absl::StrContains(cancelled.out,
                                "0 iterations, tets 7 -> 7, max edge-midpoint "
                                "error unknown, cancelled"))
      << cancelled.out;
}

// A run whose error vanished (the mesh represents the volume exactly): the zero is drawn as a
// triangle on the error panel's bottom edge and the line goes down to it; it used to end at the
// last positive error, as if the run had stopped there.
TEST(CliPlot, AZeroErrorIsATriangleOnTheBottomEdge) {
  ScratchDir dir;
  WriteBytes(
      dir.File("z.json"),
      StatsJson("longest-edge", 0.1, {{1000, 3000, 0.5}, {3000, 9000, 0.2}}, 0.0, "converged"));
  const ProcessResult run = RunTetrefine({"plot", "--stats-json", dir.File("z.json"), "--output",
                                          dir.File("z.png"), "--width", "800", "--height", "360"});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  absl::StatusOr<Image> image = DecodePng(ReadBytes(dir.File("z.png")));
  ASSERT_TRUE(image.ok()) << image.status();
  render::ConvergenceOptions options;
  options.width = 800;
  options.height = 360;
  options.epsilons = {0.1};
  const std::vector<render::ConvergenceSeries> series = {{"", {0.5, 0.2, 0.0}, {1000, 3000, 9000}}};
  absl::StatusOr<render::ConvergenceLayout> layout = render::LayoutConvergencePlot(series, options);
  ASSERT_TRUE(layout.ok()) << layout.status();
  const render::PlotArea& error = layout->error;
  const render::Rgb colour = render::SeriesColour(0);
  // The triangle's body, just above its tip on the bottom edge.
  EXPECT_EQ(image->At(static_cast<int>(std::floor(error.X(2))),
                      static_cast<int>(std::floor(error.ZeroY())) - 3),
            colour);
  // The line from iteration 1 down to it, half-way.
  const double x = (error.X(1) + error.X(2)) / 2;
  const double y = (error.Y(0.2) + error.ZeroY()) / 2;
  int near = 0;
  for (int dy = -4; dy <= 4; ++dy) {
    for (int dx = -4; dx <= 4; ++dx) {
      near += image->At(static_cast<int>(x) + dx, static_cast<int>(y) + dy) == colour;
    }
  }
  EXPECT_GT(near, 0) << "no line between the last positive error and the zero";
}

struct BadCase {
  std::string name;
  std::vector<std::string> args;  // "$D/" is replaced by the scratch directory
  std::string expected;           // must appear in the error line ("$D/" replaced too)
};

void PrintTo(const BadCase& c, std::ostream* os) { *os << c.name; }

std::string Expand(std::string text, const std::string& dir) {
  for (size_t at = text.find("$D/"); at != std::string::npos; at = text.find("$D/")) {
    text.replace(at, 3, dir + "/");
  }
  return text;
}

std::set<std::string> Listing(const std::string& dir) {
  std::set<std::string> names;
  for (const auto& entry : std::filesystem::directory_iterator(dir)) {
    names.insert(entry.path().filename().string());
  }
  return names;
}

class CliPlotBadInput : public ::testing::TestWithParam<BadCase> {
 protected:
  static void SetUpTestSuite() {
    dir_ = new ScratchDir();
    WriteBytes(dir_->File("a.json"), RunA());
    WriteBytes(dir_->File("bad.json"), "{\"options\": {\"epsilon\": 0.1}, \"iterations\": [\n");
    WriteBytes(dir_->File("empty.json"), StatsJson("paper", 0.1, {}, 0.05, "converged"));
    // "converged" with a final error above epsilon (an outside review drew such a file, its
    // axis up to 1e300, 2026-11-28).
    WriteBytes(dir_->File("contradiction.json"),
               StatsJson("paper", 0.1, {{1000, 3000, 0.5}}, 1e300, "converged"));
    WriteBytes(dir_->File("no_eps.json"), R"({"options": {"scheme": "paper"}, "iterations": []})");
  }
  static void TearDownTestSuite() {
    delete dir_;
    dir_ = nullptr;
  }
  static ScratchDir* dir_;
};

ScratchDir* CliPlotBadInput::dir_ = nullptr;

TEST_P(CliPlotBadInput, OneLineNamingTheProblemExitTwoNothingWritten) {
  const BadCase& c = GetParam();
  std::vector<std::string> args = {"plot"};
  for (const std::string& a : c.args) args.push_back(Expand(a, dir_->path()));
  const std::set<std::string> before = Listing(dir_->path());
  const ProcessResult run = RunTetrefine(args, "", /*timeout_seconds=*/60);
  EXPECT_EQ(run.exit_code, 2) << run.err;
  const std::vector<std::string> lines = SplitLines(run.err);
  ASSERT_EQ(lines.size(), 1u) << "stderr:\n" << run.err;
  const std::string expected = Expand(c.expected, dir_->path());
  EXPECT_TRUE(absl::StartsWith(lines[0], "tetrefine: ")) << lines[0];
  EXPECT_TRUE(absl::StrContains(lines[0], expected))
      << "'" << lines[0] << "' should contain '" << expected << "'";
  EXPECT_EQ(run.out, "");
  EXPECT_EQ(Listing(dir_->path()), before) << "a file was created or removed";
}

std::vector<std::string> Plot(const std::string& stats, std::vector<std::string> extra = {}) {
  std::vector<std::string> args = {"--stats-json", stats, "--output", "$D/c.png"};
  args.insert(args.end(), extra.begin(), extra.end());
  return args;
}

INSTANTIATE_TEST_SUITE_P(
    Flags, CliPlotBadInput,
    ::testing::Values(
        BadCase{"missing_file", Plot("$D/none.json"), "$D/none.json"},
        BadCase{"bad_json", Plot("$D/bad.json"),
                "$D/bad.json: not valid JSON: parse error at line 2"},
        BadCase{"no_iterations_no_input", Plot("$D/empty.json"),
                "$D/empty.json: input: missing: with no iteration"},
        BadCase{"no_epsilon", Plot("$D/no_eps.json"), "$D/no_eps.json: options.epsilon: missing"},
        BadCase{"converged_above_epsilon", Plot("$D/contradiction.json"),
                "$D/contradiction.json: final_max_error: 1e+300 is above options.epsilon 0.1, but "
                "stop_reason is \"converged\""},
        BadCase{"second_file_bad", Plot("$D/a.json", {"--stats-json", "$D/bad.json"}),
                "$D/bad.json: not valid JSON"},
        BadCase{"not_png",
                {"--stats-json", "$D/a.json", "--output", "$D/c.jpg"},
                "$D/c.jpg: --output takes a .png file"},
        BadCase{"no_output_dir",
                {"--stats-json", "$D/a.json", "--output", "$D/no/c.png"},
                "$D/no/c.png: directory $D/no does not exist (--output)"},
        BadCase{"missing_output", {"--stats-json", "$D/a.json"}, "missing required flag --output"},
        BadCase{"missing_stats", {"--output", "$D/c.png"}, "missing required flag --stats-json"},
        BadCase{"too_many_labels", Plot("$D/a.json", {"--label", "x", "--label", "y"}),
                "--label: 2 labels for 1 --stats-json files"},
        BadCase{"width_text", Plot("$D/a.json", {"--width", "wide"}),
                "--width: expected a whole number, got 'wide'"},
        BadCase{"width_too_small", Plot("$D/a.json", {"--width", "300"}),
                "$D/c.png: width 300 is too small"},
        BadCase{"height_too_small", Plot("$D/a.json", {"--height", "160"}),
                "$D/c.png: height 160 is too small"},
        BadCase{"output_twice", Plot("$D/a.json", {"--output", "$D/d.png"}),
                "--output given twice"}),
    [](const ::testing::TestParamInfo<BadCase>& info) { return info.param.name; });

}  // namespace
}  // namespace tetrefine::clitest
