// client/render: the plane's pixel grid, tet sections, tet location, sampling, colours and the
// PNG figure (decoded again with Cairo and checked pixel by pixel).

#include <algorithm>
#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "absl/strings/match.h"
#include "client/render/colormap.h"
#include "client/render/display_range.h"
#include "client/render/plane_section.h"
#include "client/render/slice_figure.h"
#include "client/render/slice_plane.h"
#include "client/render/slice_sampling.h"
#include "client/render/tet_locator.h"
#include "gtest/gtest.h"
#include "tests/render/png_image.h"
#include "tests/support/geometry.h"

namespace tetrefine::render {
namespace {

using tetrefine::testing::AnalyticVolume;
using tetrefine::testing::FiveTetMesh;
using tetrefine::testing::Seeds;

GridGeometry Grid(const Index3& dims, const Vec3& origin, const Vec3& spacing) {
  GridGeometry g;
  g.dims = dims;
  g.origin = origin;
  g.spacing = spacing;
  return g;
}

// A 10 x 10 x 10 mm box sampled every millimetre, origin at 0.
const GridGeometry kBox = Grid({11, 11, 11}, {0, 0, 0}, {1, 1, 1});

double Linear(const Vec3& p) { return 3.0 * p[0] - 2.0 * p[1] + 0.5 * p[2] + 7.0; }

TEST(SlicePlane, InPlaneAxesPixelCentresAndSizes) {
  const Volume volume =
      AnalyticVolume(Grid({11, 21, 6}, {-5, 0, 2}, {1, 0.5, 2}), [](const Vec3&) { return 0.0; });
  // The box is [-5, 5] x [0, 10] x [2, 12]: square on every plane.
  struct Case {
    int axis, u, v;
  };
  for (const Case c : {Case{2, 0, 1}, Case{1, 0, 2}, Case{0, 1, 2}}) {
    const double position = c.axis == 0 ? 1.0 : c.axis == 1 ? 4.0 : 7.0;
    absl::StatusOr<SlicePlane> plane = MakeSlicePlane(volume, c.axis, position, 50);
    ASSERT_TRUE(plane.ok()) << plane.status();
    EXPECT_EQ(plane->u_axis, c.u);
    EXPECT_EQ(plane->v_axis, c.v);
    EXPECT_EQ(plane->width, 50);
    EXPECT_EQ(plane->height, 50);
    const Vec3 top_left = plane->PixelCentre(0, 0);
    EXPECT_DOUBLE_EQ(top_left[c.axis], position);
    EXPECT_DOUBLE_EQ(top_left[c.u], plane->u_lo + 0.1);  // 10 mm over 50 pixels
    EXPECT_DOUBLE_EQ(top_left[c.v], plane->v_hi - 0.1);  // row 0 is the top
    const Vec3 p = plane->PixelCentre(17, 33);
    const auto [x, y] = plane->ToPixel(p[c.u], p[c.v]);
    EXPECT_NEAR(x, 17.5, 1e-9);
    EXPECT_NEAR(y, 33.5, 1e-9);
  }
  // Not square: the longer side gets the panel size.
  const Volume wide =
      AnalyticVolume(Grid({21, 6, 3}, {0, 0, 0}, {1, 1, 1}), [](const Vec3&) { return 0.0; });
  absl::StatusOr<SlicePlane> plane = MakeSlicePlane(wide, 2, 1.0, 200);
  ASSERT_TRUE(plane.ok());
  EXPECT_EQ(plane->width, 200);
  EXPECT_EQ(plane->height, 50);
}

TEST(SlicePlane, RefusesAPositionOutsideTheVolumeNamingTheFlagAndTheRange) {
  const Volume volume = AnalyticVolume(kBox, [](const Vec3&) { return 0.0; });
  absl::StatusOr<SlicePlane> plane = MakeSlicePlane(volume, 1, 10.5, 100);
  ASSERT_FALSE(plane.ok());
  EXPECT_EQ(plane.status().message(),
            "--position: 10.5 mm is outside the volume's y range [0, 10] mm");
  EXPECT_TRUE(MakeSlicePlane(volume, 1, 10.0, 100).ok());  // the last sample is inside
  EXPECT_TRUE(absl::StartsWith(MakeSlicePlane(volume, 1, 5, 4).status().message(),
                               "--panel-size: must be at least 8"));
}

double PolygonArea(const std::vector<std::array<double, 2>>& corners) {
  double twice = 0.0;
  for (size_t i = 0; i < corners.size(); ++i) {
    const auto& a = corners[i];
    const auto& b = corners[(i + 1) % corners.size()];
    twice += a[0] * b[1] - a[1] * b[0];
  }
  return std::abs(twice) / 2.0;
}

// The sections of a mesh that fills a box tile the box's cross-section: their areas add up to
// it. Corners out of order (a bow-tie quadrilateral) or a missed edge crossing would not.
TEST(PlaneSections, TileTheCrossSectionOfAMeshThatFillsTheBox) {
  const Mesh mesh = FiveTetMesh({1, 1, 1}, {9, 8, 7}, {3, 4, 2});
  const Volume volume = AnalyticVolume(kBox, [](const Vec3&) { return 0.0; });
  const std::array<double, 3> extent{8, 7, 6};
  for (uint64_t seed : Seeds(20)) {
    std::mt19937_64 rng(seed);
    const int axis = static_cast<int>(seed % 3);
    const double position =
        1.0 + std::uniform_real_distribution<double>(0.0, 1.0)(rng) * extent[axis];
    absl::StatusOr<SlicePlane> plane = MakeSlicePlane(volume, axis, position, 64);
    ASSERT_TRUE(plane.ok());
    const std::vector<TetSection> sections = PlaneSections(mesh, *plane);
    double area = 0.0;
    for (const TetSection& s : sections) {
      EXPECT_GE(s.corners.size(), 3u);
      EXPECT_LE(s.corners.size(), 4u);
      area += PolygonArea(s.corners);
    }
    EXPECT_NEAR(area, extent[plane->u_axis] * extent[plane->v_axis], 1e-9)
        << "seed " << seed << " axis " << axis << " position " << position;
  }
}

TEST(PlaneSections, OneTetCutThroughTheMiddleIsAQuadrilateral) {
  Mesh mesh;
  mesh.points = {{0, 0, 0}, {2, 0, 0}, {0, 2, 0}, {0, 0, 2}};
  mesh.tets = {{0, 1, 2, 3}};
  const Volume volume =
      AnalyticVolume(Grid({3, 3, 3}, {0, 0, 0}, {1, 1, 1}), [](const Vec3&) { return 0.0; });
  // x = 1 cuts edges 0-1 at its middle only: a triangle (the plane passes one vertex side).
  absl::StatusOr<SlicePlane> plane = MakeSlicePlane(volume, 0, 1.0, 16);
  ASSERT_TRUE(plane.ok());
  std::vector<TetSection> sections = PlaneSections(mesh, *plane);
  ASSERT_EQ(sections.size(), 1u);
  EXPECT_EQ(sections[0].corners.size(), 3u);
  EXPECT_NEAR(PolygonArea(sections[0].corners), 0.5, 1e-12);  // legs of 1 in (y, z)
  // A plane through the vertex x = 2 only touches: no section.
  plane = MakeSlicePlane(volume, 0, 2.0, 16);
  ASSERT_TRUE(plane.ok());
  EXPECT_TRUE(PlaneSections(mesh, *plane).empty());
}

TEST(PlaneTetLocator, FindsTheTetThatContainsEachPointAndNothingOutside) {
  const Mesh mesh = FiveTetMesh({1, 1, 1}, {9, 9, 9}, {4, 4, 4});
  const Volume volume = AnalyticVolume(kBox, [](const Vec3&) { return 0.0; });
  for (uint64_t seed : Seeds(10)) {
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> inside(1.0, 9.0), anywhere(0.0, 10.0);
    // Every other seed cuts exactly at a layer of vertices, where points lie on shared faces.
    const double position = seed % 2 == 0 ? 3.0 : inside(rng);
    absl::StatusOr<SlicePlane> plane = MakeSlicePlane(volume, 2, position, 64);
    ASSERT_TRUE(plane.ok());
    const PlaneTetLocator locator(mesh, *plane);
    for (int n = 0; n < 500; ++n) {
      const Vec3 p{anywhere(rng), anywhere(rng), position};
      const bool in_mesh = p[0] >= 1 && p[0] <= 9 && p[1] >= 1 && p[1] <= 9;
      const std::optional<PlaneTetLocator::Hit> hit = locator.Locate(p);
      ASSERT_EQ(hit.has_value(), in_mesh) << "seed " << seed << " point " << p[0] << ", " << p[1];
      if (!hit) continue;
      Vec3 back{0, 0, 0};
      double sum = 0.0;
      for (int c = 0; c < 4; ++c) {
        EXPECT_GE(hit->weights[c], -1e-9);
        sum += hit->weights[c];
        for (int a = 0; a < 3; ++a) {
          back[a] += hit->weights[c] * mesh.points[mesh.tets[hit->tet][c]][a];
        }
      }
      EXPECT_NEAR(sum, 1.0, 1e-12);
      for (int a = 0; a < 3; ++a) EXPECT_NEAR(back[a], p[a], 1e-9);
    }
  }
}

TEST(SampleSlice, ALinearFieldHasNoDiscrepancyAnywhere) {
  const Volume volume = AnalyticVolume(kBox, Linear);
  Mesh mesh = FiveTetMesh({0, 0, 0}, {10, 10, 10}, {2, 3, 2});
  mesh.values = VertexValues(volume, mesh);
  for (int axis = 0; axis < 3; ++axis) {
    absl::StatusOr<SlicePlane> plane = MakeSlicePlane(volume, axis, 4.3, 40);
    ASSERT_TRUE(plane.ok());
    const SliceSamples s = SampleSlice(volume, mesh, *plane, 100.0);
    EXPECT_EQ(s.covered_pixels, plane->width * plane->height);
    EXPECT_LT(s.max_discrepancy, 1e-12);
    for (size_t i = 0; i < s.trilinear.size(); ++i) {
      const Vec3 p = plane->PixelCentre(static_cast<int>(i % plane->width),
                                        static_cast<int>(i / plane->width));
      EXPECT_NEAR(s.trilinear[i], Linear(p), 1e-9);
      EXPECT_NEAR(s.linear[i], Linear(p), 1e-9);
    }
  }
}

// An oblique grid (rotated 30 degrees about z): the plane spans the rotated grid's world bounds,
// pixels inside the grid sample the field, pixels outside are NaN (background), and a mesh in the
// grid's frame interpolates the linear field exactly where it covers the plane.
TEST(SampleSlice, AnObliqueGridIsCutInItsWorldBoundsAndBlankOutside) {
  GridGeometry g = Grid({11, 11, 11}, {3, -2, 1}, {1, 1, 1});
  const double c = std::cos(M_PI / 6), s = std::sin(M_PI / 6);
  g.direction = {c, -s, 0, s, c, 0, 0, 0, 1};
  const Volume volume = AnalyticVolume(g, Linear);
  Mesh mesh = FiveTetMesh({0, 0, 0}, {10, 10, 10}, {2, 3, 2});
  for (Vec3& p : mesh.points) p = WorldOfIndex(g, p);
  mesh.values = VertexValues(volume, mesh);
  absl::StatusOr<SlicePlane> plane = MakeSlicePlane(volume, 2, 5.3, 60);
  ASSERT_TRUE(plane.ok()) << plane.status();
  // World bounds of the rotated square: x in [3 - 10 s, 3 + 10 c], y in [-2, -2 + 10 (s + c)].
  EXPECT_NEAR(plane->u_lo, 3 - 10 * s, 1e-12);
  EXPECT_NEAR(plane->u_hi, 3 + 10 * c, 1e-12);
  EXPECT_NEAR(plane->v_hi, -2 + 10 * (s + c), 1e-12);
  // The box's edge as a user types it (the rounded value) is on the edge, not outside it; a
  // position past it is refused with digits enough to see by how much.
  const double x_hi = 3 + 10 * c;
  for (double typed : {x_hi, std::nextafter(x_hi, 100.0), x_hi + 1e-12, x_hi - 1e-12}) {
    absl::StatusOr<SlicePlane> edge = MakeSlicePlane(volume, 0, typed, 60);
    ASSERT_TRUE(edge.ok()) << edge.status();
    EXPECT_LE(edge->position, plane->u_hi);
  }
  EXPECT_EQ(MakeSlicePlane(volume, 0, x_hi + 1e-6, 60).status().message(),
            "--position: 11.66025504 mm is outside the volume's x range [-2, 11.66025404] mm");
  const SliceSamples samples = SampleSlice(volume, mesh, *plane, 100.0);
  int inside = 0, outside = 0;
  for (size_t i = 0; i < samples.trilinear.size(); ++i) {
    const Vec3 p =
        plane->PixelCentre(static_cast<int>(i % plane->width), static_cast<int>(i / plane->width));
    if (volume.Contains(volume.ContinuousIndex(p))) {
      ++inside;
      EXPECT_NEAR(samples.trilinear[i], Linear(p), 1e-9) << i;
    } else {
      ++outside;
      EXPECT_TRUE(std::isnan(samples.trilinear[i])) << i;
      EXPECT_TRUE(std::isnan(samples.discrepancy[i])) << i;
    }
    if (!std::isnan(samples.linear[i])) {
      EXPECT_NEAR(samples.linear[i], Linear(p), 1e-9) << i;
    }
  }
  EXPECT_GT(inside, 0);
  EXPECT_GT(outside, 0);
  EXPECT_GT(samples.covered_pixels, 0);
  EXPECT_LT(samples.max_discrepancy, 1e-12);
}

// A step between x = 5 and x = 6 and a mesh with vertices every 2 mm along x: the mesh ramps
// over [4, 6] where the volume ramps over [5, 6]. Expected discrepancy at x (normCoeff 1):
// |trilinear(x) - linear(x)|, zero outside [4, 6], 0.5 at x = 5.
double StepDiscrepancy(double x) {
  const double trilinear = std::clamp(x - 5.0, 0.0, 1.0);
  const double linear = std::clamp((x - 4.0) / 2.0, 0.0, 1.0);
  return std::abs(trilinear - linear);
}

Volume StepVolume() {
  return AnalyticVolume(kBox, [](const Vec3& p) { return p[0] >= 6.0 ? 1.0 : 0.0; });
}

Mesh StepMesh(const Volume& volume) {
  Mesh mesh = FiveTetMesh({0, 0, 0}, {10, 10, 10}, {5, 2, 2});
  mesh.values = VertexValues(volume, mesh);
  return mesh;
}

TEST(SampleSlice, AStepIsWrongOnlyWhereTheMeshCannotFollowIt) {
  const Volume volume = StepVolume();
  const Mesh mesh = StepMesh(volume);
  absl::StatusOr<SlicePlane> plane = MakeSlicePlane(volume, 2, 3.7, 100);
  ASSERT_TRUE(plane.ok());
  const SliceSamples s = SampleSlice(volume, mesh, *plane, 1.0);
  for (size_t i = 0; i < s.discrepancy.size(); ++i) {
    const Vec3 p =
        plane->PixelCentre(static_cast<int>(i % plane->width), static_cast<int>(i / plane->width));
    EXPECT_NEAR(s.discrepancy[i], StepDiscrepancy(p[0]), 1e-9) << "x " << p[0];
  }
  EXPECT_NEAR(s.max_discrepancy, StepDiscrepancy(4.95), 1e-9);  // the pixel nearest x = 5
}

TEST(VertexValues, TheMeshsOwnValuesWinOverSampling) {
  const Volume volume = AnalyticVolume(kBox, Linear);
  Mesh mesh = FiveTetMesh({1, 1, 1}, {9, 9, 9}, {1, 1, 1});
  const std::vector<double> sampled = VertexValues(volume, mesh);
  for (size_t i = 0; i < mesh.points.size(); ++i) {
    EXPECT_NEAR(sampled[i], Linear(mesh.points[i]), 1e-9);
  }
  mesh.values.assign(mesh.points.size(), 42.0);
  EXPECT_EQ(VertexValues(volume, mesh), mesh.values);
}

TEST(Colormap, EndsClampingAndNoMesh) {
  EXPECT_EQ(ValueColour(0.0), (Rgb{68, 1, 84}));
  EXPECT_EQ(ValueColour(1.0), (Rgb{253, 231, 37}));
  EXPECT_EQ(ValueColour(-3.0), ValueColour(0.0));
  EXPECT_EQ(ValueColour(7.0), ValueColour(1.0));
  EXPECT_EQ(DiscrepancyColour(0.0), (Rgb{0, 0, 4}));
  EXPECT_EQ(DiscrepancyColour(1.0), (Rgb{252, 255, 164}));
  EXPECT_EQ(ValueColour(NAN), kNoMeshColour);
  EXPECT_EQ(DiscrepancyColour(NAN), kNoMeshColour);
  // Brighter means more discrepancy: luminance never falls along the map.
  double last = -1.0;
  for (int i = 0; i <= 200; ++i) {
    const Rgb c = DiscrepancyColour(i / 200.0);
    const double luminance = 0.2126 * c.r + 0.7152 * c.g + 0.0722 * c.b;
    EXPECT_GE(luminance, last - 0.5) << "t " << i / 200.0;
    last = luminance;
  }
}

TEST(DiscrepancyScale, RoundsUpToARoundNumberAboveAFloor) {
  EXPECT_DOUBLE_EQ(DiscrepancyScale(0.0), 0.01);
  EXPECT_DOUBLE_EQ(DiscrepancyScale(1e-16), 0.01);
  EXPECT_DOUBLE_EQ(DiscrepancyScale(0.01), 0.01);
  EXPECT_DOUBLE_EQ(DiscrepancyScale(0.0101), 0.015);
  EXPECT_DOUBLE_EQ(DiscrepancyScale(0.2), 0.2);
  EXPECT_DOUBLE_EQ(DiscrepancyScale(0.279), 0.3);
  EXPECT_DOUBLE_EQ(DiscrepancyScale(0.47), 0.5);
  EXPECT_DOUBLE_EQ(DiscrepancyScale(0.81), 1.0);
  EXPECT_DOUBLE_EQ(DiscrepancyScale(1.0), 1.0);
  for (double d = 0.011; d < 5; d *= 1.37) {
    EXPECT_GE(DiscrepancyScale(d), d);
    EXPECT_LE(DiscrepancyScale(d), 1.5 * d);
  }
}

TEST(BarLabel, SixDigitsAndZeroForWhatIsNothingOnTheBar) {
  EXPECT_EQ(BarLabel(1.96182e-44, 1.96182e-44, 1234.5), "0");
  EXPECT_EQ(BarLabel(-1e-300, -1e-300, 0.02), "0");
  EXPECT_EQ(BarLabel(617.25, 0, 1234.5), "617.25");
  EXPECT_EQ(BarLabel(1234.5678, 0, 1234.5678), "1234.57");
  EXPECT_EQ(BarLabel(1e-12, 1e-12, 2e-12), "1e-12");  // a bar of tiny values keeps them
  EXPECT_EQ(BarLabel(-3, -3, 5), "-3");
  EXPECT_EQ(BarLabel(0, 0, 0), "0");
}

TEST(DisplayRange, LeavesOutliersOutAndFallsBackToTheWholeRange) {
  const GridGeometry g = Grid({10, 10, 10}, {0, 0, 0}, {1, 1, 1});
  int n = 0;
  std::vector<double> values(1000);
  for (double& v : values) v = n++;  // 0 ... 999
  values[17] = 1e6;
  values[600] = -1e6;
  absl::StatusOr<Volume> volume = Volume::FromDoubles(g, values);
  ASSERT_TRUE(volume.ok());
  const std::array<double, 2> range = DisplayRange(*volume);
  EXPECT_GT(range[0], 0.0);
  EXPECT_LT(range[0], 10.0);
  EXPECT_GT(range[1], 990.0);
  EXPECT_LT(range[1], 999.0);
  values.assign(1000, 5.0);
  values[3] = 6.0;  // percentiles coincide: the whole range
  volume = Volume::FromDoubles(g, values);
  EXPECT_EQ(DisplayRange(*volume), (std::array<double, 2>{5.0, 6.0}));
}

FigureRow Row(const Volume& volume, const Mesh& mesh, const SlicePlane& plane) {
  FigureRow row;
  row.title = "row";
  row.samples = SampleSlice(volume, mesh, plane, 1.0);
  return row;
}

absl::StatusOr<testing::Image> Render(const std::vector<FigureRow>& rows,
                                      const FigureOptions& options) {
  absl::StatusOr<std::string> png = RenderSliceFigurePng(rows, options);
  if (!png.ok()) return png.status();
  return testing::DecodePng(*png);
}

// A thin plane (a 100 x 100 x 2 volume cut along x makes panels 3 pixels high): the colour bars
// keep room for their three labels, and the rows for the bars; a tall panel's bars are its height.
TEST(Figure, ColourBarsOfAThinPlaneKeepRoomForTheirLabels) {
  for (int rows : {1, 2}) {
    const FigureLayout thin = LayoutFigure(rows, 320, 3);
    for (const FigureLayout::Row& row : thin.rows) {
      EXPECT_EQ(row.volume.height, 3);
      EXPECT_EQ(row.value_bar.height, kMinColourBarHeight);
      EXPECT_EQ(row.discrepancy_bar.height, kMinColourBarHeight);
    }
    EXPECT_GE(thin.height, thin.rows.back().value_bar.y + kMinColourBarHeight);
    if (rows == 2) {
      EXPECT_GT(thin.rows[1].value_bar.y, thin.rows[0].value_bar.y + kMinColourBarHeight);
    }
  }
  const FigureLayout tall = LayoutFigure(1, 200, 320);
  EXPECT_EQ(tall.rows[0].value_bar.height, 320);
  EXPECT_EQ(tall.rows[0].discrepancy_bar.height, 320);
}

TEST(Figure, PanelsShowTheSamplesPixelForPixel) {
  const Volume volume = AnalyticVolume(kBox, Linear);
  Mesh mesh = FiveTetMesh({0, 0, 0}, {10, 10, 10}, {2, 2, 2});
  mesh.values = VertexValues(volume, mesh);
  absl::StatusOr<SlicePlane> plane = MakeSlicePlane(volume, 1, 6.2, 60);
  ASSERT_TRUE(plane.ok());
  FigureOptions options;
  options.value_lo = -13.0;
  options.value_hi = 37.0;
  options.discrepancy_max = 0.05;
  options.draw_edges = false;
  const FigureRow row = Row(volume, mesh, *plane);
  absl::StatusOr<testing::Image> image = Render({row}, options);
  ASSERT_TRUE(image.ok()) << image.status();
  const FigureLayout layout = LayoutFigure(1, plane->width, plane->height);
  ASSERT_EQ(image->width, layout.width);
  ASSERT_EQ(image->height, layout.height);
  const FigureLayout::Row& at = layout.rows[0];
  int checked = 0;
  for (int r = 0; r < plane->height; ++r) {
    for (int c = 0; c < plane->width; ++c) {
      const size_t i = static_cast<size_t>(r) * plane->width + c;
      const double t = (row.samples.trilinear[i] + 13.0) / 50.0;
      ASSERT_EQ(image->At(at.volume.x + c, at.volume.y + r), ValueColour(t)) << c << ", " << r;
      ASSERT_EQ(image->At(at.mesh.x + c, at.mesh.y + r),
                ValueColour((row.samples.linear[i] + 13.0) / 50.0));
      // A linear field: the discrepancy panel is the zero colour everywhere.
      ASSERT_EQ(image->At(at.discrepancy.x + c, at.discrepancy.y + r), DiscrepancyColour(0.0));
      ++checked;
    }
  }
  EXPECT_EQ(checked, 3600);
  // The discrepancy colour bar runs from its top colour down to zero.
  EXPECT_EQ(image->At(at.discrepancy_bar.x + 5, at.discrepancy_bar.y), DiscrepancyColour(1.0));
  EXPECT_EQ(image->At(at.discrepancy_bar.x + 5, at.discrepancy_bar.y + plane->height - 1),
            DiscrepancyColour(0.0));
}

TEST(Figure, TheDiscrepancyPanelLightsUpAtTheStepOnly) {
  const Volume volume = StepVolume();
  const Mesh mesh = StepMesh(volume);
  absl::StatusOr<SlicePlane> plane = MakeSlicePlane(volume, 2, 3.7, 100);
  ASSERT_TRUE(plane.ok());
  FigureOptions options;
  options.discrepancy_max = 0.5;
  options.draw_edges = false;
  absl::StatusOr<testing::Image> image = Render({Row(volume, mesh, *plane)}, options);
  ASSERT_TRUE(image.ok()) << image.status();
  const FigureLayout::Row at = LayoutFigure(1, plane->width, plane->height).rows[0];
  const Rgb zero = DiscrepancyColour(0.0);
  int bright = 0;
  for (int c = 0; c < plane->width; ++c) {
    const double x = plane->PixelCentre(c, 0)[0];
    for (int r = 0; r < plane->height; r += 7) {
      const Rgb pixel = image->At(at.discrepancy.x + c, at.discrepancy.y + r);
      if (x < 3.9 || x > 6.1) {
        ASSERT_EQ(pixel, zero) << "x " << x;
      } else if (x > 4.2 && x < 5.8) {
        ASSERT_NE(pixel, zero) << "x " << x;
        EXPECT_EQ(pixel, DiscrepancyColour(StepDiscrepancy(x) / 0.5)) << "x " << x;
        ++bright;
      }
    }
  }
  EXPECT_GT(bright, 100);
}

double DistanceToSegment(double px, double py, std::array<double, 2> a, std::array<double, 2> b) {
  const double dx = b[0] - a[0], dy = b[1] - a[1];
  const double length2 = dx * dx + dy * dy;
  const double t =
      length2 > 0 ? std::clamp(((px - a[0]) * dx + (py - a[1]) * dy) / length2, 0.0, 1.0) : 0.0;
  return std::hypot(px - (a[0] + t * dx), py - (a[1] + t * dy));
}

TEST(Figure, EdgesAreDrawnAlongTheSectionsAndNowhereElse) {
  const Volume volume = AnalyticVolume(kBox, Linear);
  // Not symmetric on the plane, so edges drawn mirrored or shifted would show.
  Mesh mesh = FiveTetMesh({1, 2, 1}, {9, 9, 6}, {2, 3, 2});
  mesh.values = VertexValues(volume, mesh);
  absl::StatusOr<SlicePlane> plane = MakeSlicePlane(volume, 0, 3.3, 80);
  ASSERT_TRUE(plane.ok());
  const FigureRow row = Row(volume, mesh, *plane);
  ASSERT_FALSE(row.samples.sections.empty());
  FigureOptions options;
  options.value_lo = -20;
  options.value_hi = 40;
  options.draw_edges = false;
  absl::StatusOr<testing::Image> plain = Render({row}, options);
  options.draw_edges = true;
  absl::StatusOr<testing::Image> edged = Render({row}, options);
  ASSERT_TRUE(plain.ok() && edged.ok());
  const FigureLayout::Row at = LayoutFigure(1, plane->width, plane->height).rows[0];
  // Section sides in panel pixel coordinates, by the documented convention (u to the right,
  // v up, pixel centres at half pixels) rather than through ToPixel.
  const auto to_pixel = [&](const std::array<double, 2>& p) {
    return std::array<double, 2>{
        (p[0] - plane->u_lo) / (plane->u_hi - plane->u_lo) * plane->width,
        (plane->v_hi - p[1]) / (plane->v_hi - plane->v_lo) * plane->height};
  };
  std::vector<std::array<std::array<double, 2>, 2>> sides;
  for (const TetSection& s : row.samples.sections) {
    for (size_t i = 0; i < s.corners.size(); ++i) {
      sides.push_back({to_pixel(s.corners[i]), to_pixel(s.corners[(i + 1) % s.corners.size()])});
    }
  }
  int changed = 0;
  for (const PixelRect& panel : {at.mesh, at.discrepancy}) {
    for (int r = 0; r < plane->height; ++r) {
      for (int c = 0; c < plane->width; ++c) {
        if (plain->At(panel.x + c, panel.y + r) == edged->At(panel.x + c, panel.y + r)) continue;
        ++changed;
        double nearest = INFINITY;
        for (const auto& side : sides) {
          nearest = std::min(nearest, DistanceToSegment(c + 0.5, r + 0.5, side[0], side[1]));
        }
        ASSERT_LE(nearest, 1.2) << "pixel " << c << ", " << r << " changed far from any edge";
      }
    }
  }
  EXPECT_GT(changed, 2 * plane->width);
  // The volume panel has no edges.
  for (int r = 0; r < plane->height; ++r) {
    for (int c = 0; c < plane->width; ++c) {
      ASSERT_EQ(plain->At(at.volume.x + c, at.volume.y + r),
                edged->At(at.volume.x + c, at.volume.y + r));
    }
  }
}

TEST(Figure, UncoveredPixelsAreWhiteAndTwoRowsStack) {
  const Volume volume = AnalyticVolume(kBox, Linear);
  Mesh small = FiveTetMesh({2, 2, 2}, {5, 5, 5}, {1, 1, 1});
  small.values = VertexValues(volume, small);
  Mesh whole = FiveTetMesh({0, 0, 0}, {10, 10, 10}, {1, 1, 1});
  whole.values = VertexValues(volume, whole);
  absl::StatusOr<SlicePlane> plane = MakeSlicePlane(volume, 2, 3.0, 50);
  ASSERT_TRUE(plane.ok());
  FigureOptions options;
  options.value_lo = -20;
  options.value_hi = 40;
  options.draw_edges = false;
  absl::StatusOr<testing::Image> image =
      Render({Row(volume, small, *plane), Row(volume, whole, *plane)}, options);
  ASSERT_TRUE(image.ok()) << image.status();
  const FigureLayout layout = LayoutFigure(2, plane->width, plane->height);
  ASSERT_EQ(image->height, layout.height);
  ASSERT_GT(layout.rows[1].mesh.y, layout.rows[0].mesh.y + plane->height);
  const auto [c, r] = plane->ToPixel(8.0, 8.0);  // outside the small mesh, inside the whole
  const int col = static_cast<int>(c), row = static_cast<int>(r);
  EXPECT_EQ(image->At(layout.rows[0].mesh.x + col, layout.rows[0].mesh.y + row), kNoMeshColour);
  EXPECT_EQ(image->At(layout.rows[0].discrepancy.x + col, layout.rows[0].discrepancy.y + row),
            kNoMeshColour);
  EXPECT_NE(image->At(layout.rows[1].mesh.x + col, layout.rows[1].mesh.y + row), kNoMeshColour);

  absl::StatusOr<SlicePlane> other = MakeSlicePlane(volume, 2, 3.0, 60);
  ASSERT_TRUE(other.ok());
  EXPECT_FALSE(
      RenderSliceFigurePng({Row(volume, small, *plane), Row(volume, whole, *other)}, options).ok());
}

}  // namespace
}  // namespace tetrefine::render
