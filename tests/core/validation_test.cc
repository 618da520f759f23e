// Bad input gets an InvalidArgument error that names the field and the index.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "core/refine.h"
#include "tests/support/geometry.h"
#include "tests/support/mesh_checks.h"

namespace tetrefine {
namespace {

Volume UnitVolume() {
  GridGeometry g;
  g.dims = {5, 5, 5};
  return testing::AnalyticVolume(g, [](const Vec3& p) { return p[0] * p[1] + p[2]; });
}

Mesh TwoTets() {
  Mesh m;
  m.points = {{1, 1, 1}, {2, 1, 1}, {1, 2, 1}, {1, 1, 2}, {2, 2, 2}};
  m.tets = {{0, 1, 2, 3}, {1, 2, 3, 4}};
  // The second shares face (1 2 3) with the first, on the other side.
  if (SignedVolume6(m.points[1], m.points[2], m.points[3], m.points[4]) < 0) {
    std::swap(m.tets[1][2], m.tets[1][3]);
  }
  return m;
}

struct BadCase {
  const char* name;
  void (*mutate)(Mesh&, RefineOptions&);
  const char* expected;  // a fragment of the message
};

const BadCase kCases[] = {
    {"nan coordinate", [](Mesh& m, RefineOptions&) { m.points[3][1] = std::nan(""); },
     "mesh.points[3]"},
    {"infinite coordinate",
     [](Mesh& m, RefineOptions&) { m.points[2][0] = std::numeric_limits<double>::infinity(); },
     "mesh.points[2]"},
    // Found by the refine fuzzer: 6V of such a tet overflowed to NaN and passed every check.
    {"huge coordinate", [](Mesh& m, RefineOptions&) { m.points[1][0] = 1e150; },
     "mesh.points[1] = (1e+150, 1, 1) is too large"},
    {"index out of range", [](Mesh& m, RefineOptions&) { m.tets[1][2] = 9; },
     "mesh.tets[1][2] = 9 is out of range"},
    {"repeated vertex", [](Mesh& m, RefineOptions&) { m.tets[0][3] = m.tets[0][0]; },
     "mesh.tets[0] repeats vertex"},
    {"inverted", [](Mesh& m, RefineOptions&) { std::swap(m.tets[0][0], m.tets[0][1]); },
     "mesh.tets[0] is inverted"},
    {"degenerate",
     [](Mesh& m, RefineOptions&) {
       m.points[3] = {1.5, 1.5, 1.0};
     },
     "mesh.tets[0] is degenerate"},
    {"outside",
     [](Mesh& m, RefineOptions&) {
       m.points[4] = {2, 2, 4.5};
     },
     "mesh.points[4] = (2, 2, 4.5) lies outside"},
    {"listed twice", [](Mesh& m, RefineOptions&) { m.tets[1] = m.tets[0]; }, "are the same tet"},
    {"empty", [](Mesh& m, RefineOptions&) { m.tets.clear(); }, "mesh.tets is empty"},
    {"epsilon zero", [](Mesh&, RefineOptions& o) { o.epsilon = 0; }, "options.epsilon"},
    {"epsilon negative", [](Mesh&, RefineOptions& o) { o.epsilon = -1; }, "options.epsilon"},
    {"epsilon nan", [](Mesh&, RefineOptions& o) { o.epsilon = std::nan(""); }, "options.epsilon"},
    {"norm zero", [](Mesh&, RefineOptions& o) { o.norm_coeff = 0.0; }, "options.norm_coeff"},
    {"max tets", [](Mesh&, RefineOptions& o) { o.max_tets = 0; }, "options.max_tets"},
    {"iterations", [](Mesh&, RefineOptions& o) { o.max_iterations = -1; },
     "options.max_iterations"},
};

TEST(Validation, EveryBadInputIsNamed) {
  for (const BadCase& c : kCases) {
    Mesh m = TwoTets();
    RefineOptions o;
    c.mutate(m, o);
    auto r = Refine(UnitVolume(), m, o);
    ASSERT_FALSE(r.ok()) << c.name;
    EXPECT_EQ(r.status().code(), absl::StatusCode::kInvalidArgument) << c.name;
    EXPECT_NE(r.status().message().find(c.expected), std::string::npos)
        << c.name << ": " << r.status().message();
  }
}

// The one set of option limits (core/refine_options.h): each bound, just inside and just
// outside, and the message names the field and the value.
TEST(Validation, OptionLimitsNameTheFieldAndTheValue) {
  struct Bound {
    void (*set)(RefineOptions&, bool outside);
    const char* message;
  };
  const Bound bounds[] = {
      {[](RefineOptions& o, bool out) { o.epsilon = out ? 0.0 : 1e-300; },
       "options.epsilon: must be finite and > 0, got 0"},
      {[](RefineOptions& o, bool out) { o.max_iterations = out ? -1 : 0; },
       "options.max_iterations: must be >= 0, got -1"},
      {[](RefineOptions& o, bool out) { o.max_tets = out ? kMaxTetsCeiling + 1 : kMaxTetsCeiling; },
       "options.max_tets: must be in [1, 500000000], got 500000001"},
      {[](RefineOptions& o, bool out) { o.max_tets = out ? 0 : 1; },
       "options.max_tets: must be in [1, 500000000], got 0"},
      {[](RefineOptions& o, bool out) { o.norm_coeff = out ? -2.0 : 1e-300; },
       "options.norm_coeff: must be finite and > 0, got -2"},
      {[](RefineOptions& o, bool out) { o.threads = out ? -1 : 0; },
       "options.threads: must be >= 0 (0: all cores), got -1"},
      {[](RefineOptions& o, bool out) { o.min_edge_length = out ? -0.5 : 0.0; },
       "options.min_edge_length: must be finite and >= 0, got -0.5"},
      {[](RefineOptions& o, bool out) { o.min_quality = out ? 1.0 : 0.999; },
       "options.min_quality: must be in [0, 1), got 1"},
      {[](RefineOptions& o, bool out) { o.quality_reference = out ? 0.0 : 1.0; },
       "options.quality_reference: must be in (0, 1], got 0"},
      {[](RefineOptions& o, bool out) { o.quality_reference = out ? 1.5 : 1e-300; },
       "options.quality_reference: must be in (0, 1], got 1.5"},
      {[](RefineOptions& o, bool out) { o.lattice_n = out ? 65 : 64; },
       "options.lattice_n: must be in [0, 64], got 65"},
      {[](RefineOptions& o, bool out) { o.lattice_max_tets = out ? -1 : 0; },
       "options.lattice_max_tets: must be >= 0, got -1"},
      // Order 1 is the corners, where the discrepancy is 0: a certificate of nothing (found by a
      // sweep of the CLI: `--certify --lattice-n 1` reported a certified maximum of 0 below the
      // result's own midpoint maximum); orders 2 and 3 have no point inside a tet (an outside
      // review, 2026-11-28).
      {[](RefineOptions& o, bool out) {
         o.certify = true;
         o.lattice_n = out ? 1 : 4;
       },
       "options.lattice_n: certify needs a lattice with points inside the tets (lattice_n >= 4; "
       "orders 1-3 have points on the corners, edges and faces only), got 1"},
      {[](RefineOptions& o, bool out) {
         o.certify = true;
         o.lattice_n = out ? 3 : 8;
       },
       "options.lattice_n: certify needs a lattice with points inside the tets (lattice_n >= 4; "
       "orders 1-3 have points on the corners, edges and faces only), got 3"},
  };
  EXPECT_TRUE(ValidateRefineOptions(RefineOptions{}).ok());
  for (const Bound& b : bounds) {
    RefineOptions inside;
    b.set(inside, false);
    EXPECT_TRUE(ValidateRefineOptions(inside).ok()) << b.message;
    RefineOptions outside;
    b.set(outside, true);
    const absl::Status status = ValidateRefineOptions(outside);
    EXPECT_EQ(status.code(), absl::StatusCode::kInvalidArgument);
    EXPECT_EQ(status.message(), b.message);
  }
}

// Found by a CLI sweep: values {1e16, 1e16 + 2} refined to the tet budget with "lattice max
// 2.0" (rounding, impossible in exact arithmetic), and {0, 5e-324} to 32 M tets. Volumes whose
// errors float64 cannot resolve are refused, saying what to do; the same field offset back to
// 0 refines, and so does the offset one with a normalisation its magnitude can carry.
TEST(Validation, ValuesFloat64CannotResolveAreRefused) {
  const GridGeometry grid{.dims = {6, 6, 6}, .origin = {0, 0, 0}, .spacing = {1, 1, 1}};
  const auto two_level = [&](double low, double high) {
    return testing::AnalyticVolume(grid,
                                   [&](const Vec3& p) { return p[0] + p[1] > 5 ? high : low; });
  };
  const Mesh mesh = testing::FiveTetMesh({0.5, 0.5, 0.5}, {4.5, 4.5, 4.5}, {2, 2, 2});
  RefineOptions options;
  options.epsilon = 0.05;
  options.max_iterations = 3;
  const absl::StatusOr<RefineResult> offset = Refine(two_level(1e16, 1e16 + 2), mesh, options);
  ASSERT_EQ(offset.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_NE(offset.status().message().find("subtract an offset"), std::string::npos)
      << offset.status();
  // A constant volume far from 0: normalised by 1, and said to be constant, not to "vary over
  // only 1" (an outside check, 2026-11-28).
  const absl::Status constant = CheckValuePrecision(1.0, {1e15, 1e15}, 0.1);
  EXPECT_THAT(std::string(constant.message()),
              ::testing::HasSubstr("values reach 1e+15 and are all equal (a constant volume, "
                                   "normalised by 1)"));
  EXPECT_THAT(std::string(constant.message()), ::testing::HasSubstr("subtract an offset"));
  const absl::StatusOr<RefineResult> tiny = Refine(two_level(0, 5e-324), mesh, options);
  ASSERT_EQ(tiny.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_NE(tiny.status().message().find("below 1e-290"), std::string::npos) << tiny.status();
  EXPECT_TRUE(Refine(two_level(0, 2), mesh, options).ok());
  EXPECT_TRUE(Refine(two_level(1e6, 1e6 + 2), mesh, options).ok());
  RefineOptions wide = options;
  wide.norm_coeff = 1e16;
  EXPECT_TRUE(Refine(two_level(1e16, 1e16 + 2), mesh, wide).ok());
  EXPECT_TRUE(CheckValuePrecision(4096, {-1024, 3071}, 1e-6).ok());  // an int16 CT
  // A tiny epsilon on an ordinary volume, which no offset helps: the message names epsilon and
  // ends with the smallest that passes, which does (it blamed the volume alone, then with an
  // offset as its remedy: outside reviews, 2026-11-28).
  const absl::Status small = CheckValuePrecision(4096, {-1024, 3072}, 1e-14);
  ASSERT_EQ(small.code(), absl::StatusCode::kInvalidArgument);
  const std::string text(small.message());
  EXPECT_EQ(text.rfind("options.epsilon: 1e-14 is below what float64 resolves", 0), 0u) << text;
  EXPECT_EQ(text.find("subtract an offset"), std::string::npos) << text;
  const std::string quoted = "use an epsilon of at least ";
  const size_t at = text.find(quoted);
  ASSERT_NE(at, std::string::npos) << text;
  const double least = std::stod(text.substr(at + quoted.size()));
  EXPECT_TRUE(CheckValuePrecision(4096, {-1024, 3072}, least).ok()) << least;
  EXPECT_FALSE(CheckValuePrecision(4096, {-1024, 3072}, least * 0.98).ok()) << least;
  // A norm_coeff the caller gave too small is named as such, with the smallest that passes,
  // which does (it was blamed on the volume, with remedies for the volume: an outside review of
  // the service, 2026-11-28).
  RefineOptions narrow = options;
  narrow.norm_coeff = 1e-12;
  const absl::StatusOr<RefineResult> given = Refine(two_level(0, 13), mesh, narrow);
  ASSERT_EQ(given.status().code(), absl::StatusCode::kInvalidArgument);
  const std::string said(given.status().message());
  EXPECT_EQ(said.rfind("options.norm_coeff: 1e-12 is too small for this volume", 0), 0u) << said;
  EXPECT_EQ(said.find("subtract an offset"), std::string::npos) << said;
  const std::string norm_quoted = "use a norm_coeff of at least ";
  const size_t norm_at = said.find(norm_quoted);
  ASSERT_NE(norm_at, std::string::npos) << said;
  const double smallest = std::stod(said.substr(norm_at + norm_quoted.size()));
  narrow.norm_coeff = smallest;
  EXPECT_TRUE(Refine(two_level(0, 13), mesh, narrow).ok()) << smallest;
  narrow.norm_coeff = smallest * 0.98;
  EXPECT_FALSE(Refine(two_level(0, 13), mesh, narrow).ok()) << smallest;
}

TEST(Validation, FaceInThreeTetsIsRefused) {
  Mesh m = TwoTets();
  m.points.push_back({1.2, 1.2, 0.5});
  Tet t = {1, 2, 3, 5};
  if (SignedVolume6(m.points[1], m.points[2], m.points[3], m.points[5]) < 0) std::swap(t[2], t[3]);
  m.tets.push_back(t);
  auto r = Refine(UnitVolume(), m, RefineOptions{});
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.status().message().find("is shared by 3 tets"), std::string::npos)
      << r.status().message();
}

// One tet listed twice is named as such, not
// as an overlap or a face in three tets, whichever face check meets it first.
TEST(Validation, ATetListedTwiceIsNamedAsSuch) {
  // A lone tet and its copy; a tet, its neighbour across a face, and the neighbour's copy.
  Mesh lone = TwoTets();
  lone.tets = {lone.tets[0], lone.tets[0]};
  Mesh pair = TwoTets();
  pair.tets.push_back(pair.tets[1]);
  for (const auto& [mesh, message] :
       {std::pair{lone, "mesh.tets[0] and mesh.tets[1] are the same tet"},
        std::pair{pair, "mesh.tets[1] and mesh.tets[2] are the same tet"}}) {
    auto r = Refine(UnitVolume(), mesh, RefineOptions{});
    ASSERT_FALSE(r.ok());
    EXPECT_NE(r.status().message().find(message), std::string::npos) << r.status().message();
    EXPECT_NE(r.status().message().find("an element listed twice"), std::string::npos);
  }
}

TEST(Validation, PoliciesNormalizeAndClamp) {
  Mesh m = TwoTets();
  std::swap(m.tets[0][0], m.tets[0][1]);
  m.points[4] = {2, 2, 4.5};
  RefineOptions o;
  o.orientation = OrientationPolicy::kNormalize;
  o.outside = OutsidePolicy::kClamp;
  auto r = Refine(UnitVolume(), m, o);
  ASSERT_TRUE(r.ok()) << r.status();
  EXPECT_EQ(r->tets_reoriented, 1);
}

// Refine works on the caller's points and tets until its first subdivision (no copy); with no
// subdivision the result must still be the whole validated input, reoriented where asked.
TEST(Validation, WithoutASubdivisionTheResultIsTheValidatedInput) {
  const Mesh m = TwoTets();
  RefineOptions o;
  o.max_iterations = 0;
  auto r = Refine(UnitVolume(), m, o);
  ASSERT_TRUE(r.ok()) << r.status();
  EXPECT_EQ(r->mesh.points, m.points);
  EXPECT_EQ(r->mesh.tets, m.tets);
  ASSERT_EQ(r->mesh.values.size(), m.points.size());
  for (size_t i = 0; i < m.points.size(); ++i) {
    EXPECT_EQ(r->mesh.values[i], UnitVolume().Sample(m.points[i])) << "vertex " << i;
  }

  Mesh inverted = m;
  std::swap(inverted.tets[1][0], inverted.tets[1][1]);
  o.orientation = OrientationPolicy::kNormalize;
  r = Refine(UnitVolume(), inverted, o);
  ASSERT_TRUE(r.ok()) << r.status();
  EXPECT_EQ(r->tets_reoriented, 1);
  EXPECT_EQ(r->mesh.points, m.points);
  ASSERT_EQ(r->mesh.tets.size(), 2u);
  EXPECT_EQ(r->mesh.tets[0], m.tets[0]);
  for (const Tet& t : r->mesh.tets) {
    EXPECT_GT(SignedVolume6(m.points[t[0]], m.points[t[1]], m.points[t[2]], m.points[t[3]]), 0.0);
  }
}

// A reoriented input that is then refined: the children come from the flipped tets.
TEST(Validation, ReorientedInputRefinesToPositiveConformalTets) {
  GridGeometry g;
  g.dims = {12, 12, 12};
  const Volume v = testing::AnalyticVolume(
      g, [](const Vec3& p) { return std::sin(0.9 * p[0]) * std::cos(0.7 * p[1]) + 0.1 * p[2]; });
  const Mesh good = testing::FiveTetMesh({0, 0, 0}, {11, 11, 11}, {3, 3, 3});
  Mesh flipped = good;
  for (size_t t = 0; t < flipped.tets.size(); t += 3)
    std::swap(flipped.tets[t][0], flipped.tets[t][1]);
  RefineOptions o;
  o.epsilon = 0.02;
  o.max_iterations = 3;
  o.orientation = OrientationPolicy::kNormalize;
  auto r = Refine(v, flipped, o);
  ASSERT_TRUE(r.ok()) << r.status();
  EXPECT_EQ(r->tets_reoriented, static_cast<int64_t>((good.tets.size() + 2) / 3));
  ASSERT_FALSE(r->iterations.empty());
  EXPECT_EQ(testing::ConformityProblem(good, r->mesh), "");
  // Flipping back by swapping corners 0 and 1 gives the same geometry as the good mesh's run.
  o.orientation = OrientationPolicy::kReject;
  auto reference = Refine(v, good, o);
  ASSERT_TRUE(reference.ok()) << reference.status();
  EXPECT_EQ(r->mesh.tets.size(), reference->mesh.tets.size());
  EXPECT_EQ(r->final_max_error, reference->final_max_error);
}

TEST(Volume, TrilinearMatchesEquation1AndEveryVoxelType) {
  GridGeometry g;
  g.dims = {3, 4, 5};
  g.spacing = {0.5, 2.0, 1.5};
  g.origin = {-1, 2, 3};
  std::vector<std::byte> bytes;
  std::vector<double> values;
  for (int i = 0; i < 60; ++i) {
    const int16_t v = static_cast<int16_t>((i * 37) % 101 - 50);
    values.push_back(v);
    const auto* b = reinterpret_cast<const std::byte*>(&v);
    bytes.insert(bytes.end(), b, b + 2);
  }
  auto vol16 = Volume::CreateWhole(g, VoxelType::kInt16, bytes);
  auto vol64 = Volume::FromDoubles(g, values);
  ASSERT_TRUE(vol16.ok() && vol64.ok());
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int n = 0; n < 1000; ++n) {
    const Vec3 idx = {u(rng) * 2, u(rng) * 3, u(rng) * 4};
    const Vec3 p = {g.origin[0] + idx[0] * 0.5, g.origin[1] + idx[1] * 2.0,
                    g.origin[2] + idx[2] * 1.5};
    const int i = std::min(1, static_cast<int>(idx[0]));
    const int j = std::min(2, static_cast<int>(idx[1]));
    const int k = std::min(3, static_cast<int>(idx[2]));
    const double x = idx[0] - i, y = idx[1] - j, z = idx[2] - k;
    auto I = [&](int a, int b, int c) { return values[(i + a) + 3 * ((j + b) + 4 * (k + c))]; };
    const double eq1 = (1 - x) * (1 - y) * (1 - z) * I(0, 0, 0) +
                       x * (1 - y) * (1 - z) * I(1, 0, 0) + (1 - x) * y * (1 - z) * I(0, 1, 0) +
                       x * y * (1 - z) * I(1, 1, 0) + (1 - x) * (1 - y) * z * I(0, 0, 1) +
                       x * (1 - y) * z * I(1, 0, 1) + (1 - x) * y * z * I(0, 1, 1) +
                       x * y * z * I(1, 1, 1);
    EXPECT_NEAR(vol16->Sample(p), eq1, 1e-9);
    EXPECT_EQ(vol16->Sample(p), vol64->Sample(p));
  }
  EXPECT_FALSE(Volume::CreateWhole(g, VoxelType::kInt16, {}).ok());
}

// A grid whose index map overflows float64 is refused naming the axis: a subnormal spacing made
// every index infinite and every point "inside" (a request with spacing 1e-310 refined with the
// boundary's value at every vertex), and corners beyond float64 did the same.
TEST(Volume, GridsWhoseIndexMapOverflowsAreRefused) {
  const std::vector<double> values(8, 1.0);
  GridGeometry g;
  g.dims = {2, 2, 2};
  g.spacing = {1.0, 1e-310, 1.0};
  absl::StatusOr<Volume> subnormal = Volume::FromDoubles(g, values);
  ASSERT_FALSE(subnormal.ok());
  EXPECT_THAT(
      std::string(subnormal.status().message()),
      ::testing::HasSubstr("volume.spacing.y = 1e-310: must be finite and at least 2.22507e-308"));
  g.spacing = {1.0, std::numeric_limits<double>::min(), 1.0};
  EXPECT_TRUE(Volume::FromDoubles(g, values).ok());
  g.spacing = {1.0, 1.0, 1e308};
  g.origin = {0.0, 0.0, 1e308};
  absl::StatusOr<Volume> huge = Volume::FromDoubles(g, values);
  ASSERT_FALSE(huge.ok());
  EXPECT_THAT(std::string(huge.status().message()), ::testing::HasSubstr("far corner"));
  g.direction = {0.6, -0.8, 0.0, 0.8, 0.6, 0.0, 0.0, 0.0, 1.0};
  EXPECT_FALSE(Volume::FromDoubles(g, values).ok());
}

// The documented default (README, `refine --help`): docs/results measures convergence under a
// cap of 32, and a run that stopped at the old default of 16 converges at 18
// (core/refine_options.h).
TEST(RefineOptionsTest, DefaultIterationCapIsTheOneConvergenceIsMeasuredUnder) {
  EXPECT_EQ(RefineOptions{}.max_iterations, 32);
}

}  // namespace
}  // namespace tetrefine
