// Oblique grids (GridGeometry::direction): sampling in the rotated frame equals sampling the
// axis-aligned grid at the same index, Create refuses bad directions naming the field, the
// identity keeps the axis-aligned formulas to the bit, and refinement in a rotated frame gives
// the rotated result of the axis-aligned one.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "core/refine.h"
#include "core/volume.h"
#include "tests/support/geometry.h"

namespace tetrefine {
namespace {

Vec3 Apply(const Mat3& m, const Vec3& v) {
  return {m[0] * v[0] + m[1] * v[1] + m[2] * v[2], m[3] * v[0] + m[4] * v[1] + m[5] * v[2],
          m[6] * v[0] + m[7] * v[1] + m[8] * v[2]};
}

std::vector<double> RandomValues(std::mt19937_64& rng, const Index3& dims) {
  std::uniform_real_distribution<double> value(-50.0, 50.0);
  std::vector<double> v(dims[0] * dims[1] * dims[2]);
  for (double& x : v) x = value(rng);
  return v;
}

TEST(ObliqueVolume, SamplesTheAxisAlignedValueAtTheSameIndex) {
  for (uint64_t seed : testing::Seeds(40)) {
    SCOPED_TRACE(seed);
    std::mt19937_64 rng(seed);
    std::uniform_int_distribution<int64_t> dim(2, 9);
    std::uniform_real_distribution<double> spacing(0.3, 4.0), origin(-100.0, 100.0);
    GridGeometry aligned;
    aligned.dims = {dim(rng), dim(rng), dim(rng)};
    aligned.spacing = {spacing(rng), spacing(rng), spacing(rng)};
    GridGeometry oblique = aligned;
    oblique.origin = {origin(rng), origin(rng), origin(rng)};
    oblique.direction = testing::RandomRotation(rng, seed % 2 == 1);
    const std::vector<double> values = RandomValues(rng, aligned.dims);
    const absl::StatusOr<Volume> a = Volume::FromDoubles(aligned, values);
    const absl::StatusOr<Volume> b = Volume::FromDoubles(oblique, values);
    ASSERT_TRUE(a.ok()) << a.status();
    ASSERT_TRUE(b.ok()) << b.status();
    EXPECT_TRUE(a->axis_aligned());
    EXPECT_FALSE(b->axis_aligned());
    for (int trial = 0; trial < 50; ++trial) {
      Vec3 u;
      for (int axis = 0; axis < 3; ++axis) {
        u[axis] = std::uniform_real_distribution<double>(
            0.0, static_cast<double>(aligned.dims[axis] - 1))(rng);
      }
      Vec3 scaled{u[0] * oblique.spacing[0], u[1] * oblique.spacing[1], u[2] * oblique.spacing[2]};
      const Vec3 rotated = Apply(oblique.direction, scaled);
      const Vec3 p{oblique.origin[0] + rotated[0], oblique.origin[1] + rotated[1],
                   oblique.origin[2] + rotated[2]};
      const Vec3 back = b->ContinuousIndex(p);
      for (int axis = 0; axis < 3; ++axis) EXPECT_NEAR(back[axis], u[axis], 1e-9);
      ASSERT_TRUE(b->Contains(back));
      EXPECT_NEAR(b->Sample(p), a->SampleIndex(u), 1e-9 * 50.0);
      const Vec3 world = WorldOfIndex(oblique, u);
      for (int axis = 0; axis < 3; ++axis) EXPECT_NEAR(world[axis], p[axis], 1e-9);
    }
    // A point just outside the index box is outside, whatever the rotation.
    const Vec3 outside = WorldOfIndex(oblique, {-0.01, 0.5, 0.5});
    EXPECT_FALSE(b->Contains(b->ContinuousIndex(outside)));
  }
}

TEST(ObliqueVolume, IdentityKeepsTheAxisAlignedFormulasToTheBit) {
  for (uint64_t seed : testing::Seeds(20)) {
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> spacing(0.3, 4.0), coord(-100.0, 100.0);
    GridGeometry g;
    g.dims = {5, 6, 7};
    g.spacing = {spacing(rng), spacing(rng), spacing(rng)};
    g.origin = {coord(rng), coord(rng), coord(rng)};
    const absl::StatusOr<Volume> v = Volume::FromDoubles(g, RandomValues(rng, g.dims));
    ASSERT_TRUE(v.ok());
    const Vec3 p{coord(rng), coord(rng), coord(rng)};
    const Vec3 u = v->ContinuousIndex(p);
    for (int a = 0; a < 3; ++a) {
      EXPECT_EQ(u[a], (p[a] - g.origin[a]) / g.spacing[a]);
      EXPECT_EQ(WorldOfIndex(g, p)[a], g.origin[a] + p[a] * g.spacing[a]);
    }
  }
}

TEST(ObliqueVolume, CreateRefusesBadDirectionsNamingTheField) {
  GridGeometry g;
  g.dims = {3, 3, 3};
  const std::vector<double> values(27, 1.0);
  g.direction[4] = std::nan("");
  absl::StatusOr<Volume> v = Volume::FromDoubles(g, values);
  ASSERT_FALSE(v.ok());
  EXPECT_NE(v.status().message().find("volume.direction[4]"), std::string::npos) << v.status();

  g.direction = {1.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0};  // columns 0 and 1 parallel
  v = Volume::FromDoubles(g, values);
  ASSERT_FALSE(v.ok());
  EXPECT_NE(v.status().message().find("volume.direction"), std::string::npos) << v.status();
  EXPECT_NE(v.status().message().find("singular"), std::string::npos) << v.status();

  g.direction = {0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0};  // column 0 zero
  v = Volume::FromDoubles(g, values);
  ASSERT_FALSE(v.ok());
  EXPECT_NE(v.status().message().find("column 0"), std::string::npos) << v.status();

  // An axis permutation is oblique but perfectly valid.
  g.direction = {0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 1.0, 0.0, 0.0};
  EXPECT_TRUE(Volume::FromDoubles(g, values).ok());
}

// FindDirectionDefect is the one rule the volume and the wire's header share. Over many random
// matrices: any rotation or mirror with columns scaled by arbitrary lengths is usable (the test
// is scale-free); spoiling one entry, one column or the rank is reported as exactly that defect,
// at the spoiled index.
TEST(ObliqueVolume, DirectionDefectNamesWhatIsWrongAndWhere) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> log_length(-6.0, 6.0);
  std::uniform_int_distribution<int> pick9(0, 8), pick3(0, 2);
  for (int seed = 0; seed < 200; ++seed) {
    Mat3 d = testing::RandomRotation(rng, seed % 2 == 1);
    for (int column = 0; column < 3; ++column) {
      const double length = std::pow(10.0, log_length(rng));
      for (int row = 0; row < 3; ++row) d[3 * row + column] *= length;
    }
    EXPECT_EQ(FindDirectionDefect(d).kind, DirectionDefect::Kind::kNone) << "seed " << seed;

    Mat3 not_finite = d;
    const int entry = pick9(rng);
    not_finite[entry] = seed % 3 == 0 ? std::nan("") : (seed % 3 == 1 ? 1.0 : -1.0) / 0.0;
    const DirectionDefect nf = FindDirectionDefect(not_finite);
    EXPECT_EQ(nf.kind, DirectionDefect::Kind::kNotFinite) << "seed " << seed;
    EXPECT_EQ(nf.index, entry) << "seed " << seed;

    Mat3 zero = d;
    const int column = pick3(rng);
    // A zero column, or one whose length overflows (sqrt(3) * 1.5e308 > DBL_MAX).
    const double fill = seed % 2 == 0 ? 0.0 : 1.5e308;
    for (int row = 0; row < 3; ++row) zero[3 * row + column] = fill;
    const DirectionDefect z = FindDirectionDefect(zero);
    EXPECT_EQ(z.kind, DirectionDefect::Kind::kZeroColumn) << "seed " << seed;
    EXPECT_EQ(z.index, column) << "seed " << seed;

    Mat3 parallel = d;  // column (column + 1) % 3 made a multiple of `column`
    const int other = (column + 1) % 3;
    for (int row = 0; row < 3; ++row) parallel[3 * row + other] = -3.5 * d[3 * row + column];
    const DirectionDefect s = FindDirectionDefect(parallel);
    EXPECT_EQ(s.kind, DirectionDefect::Kind::kSingular) << "seed " << seed;
    EXPECT_LT(s.det, kMinDirectionDeterminant) << "seed " << seed;
  }
}

// Refining the rotated volume with the rotated mesh gives the rotated refinement: the same
// topology and counts, points equal up to rounding.
TEST(ObliqueVolume, RefiningInARotatedFrameGivesTheRotatedResult) {
  for (uint64_t seed : testing::Seeds(6)) {
    SCOPED_TRACE(seed);
    std::mt19937_64 rng(seed);
    GridGeometry aligned;
    aligned.dims = {12, 10, 8};
    aligned.spacing = {1.5, 1.5, 2.5};
    const Vec3 hi{11 * 1.5, 9 * 1.5, 7 * 2.5};
    const Volume a = testing::AnalyticVolume(aligned, testing::TestField);
    GridGeometry oblique = aligned;
    oblique.origin = {12.0, -30.0, 7.5};
    oblique.direction = testing::RandomRotation(rng, /*mirror=*/false);
    const absl::StatusOr<Volume> b = Volume::CreateWhole(oblique, VoxelType::kFloat64, a.data());
    ASSERT_TRUE(b.ok()) << b.status();

    // Jittered so that no two edges are exactly as long: the longest-edge scheme breaks exact
    // ties by world coordinates, which a rotation does not preserve.
    Mesh mesh =
        testing::FiveTetMesh({0.5, 0.5, 0.5}, {hi[0] - 0.5, hi[1] - 0.5, hi[2] - 0.5}, {3, 3, 2});
    std::uniform_real_distribution<double> jitter(-0.3, 0.3);
    for (Vec3& p : mesh.points) {
      for (double& x : p) x += jitter(rng);
    }
    Mesh rotated = mesh;
    for (Vec3& p : rotated.points) {
      const Vec3 r = Apply(oblique.direction, p);
      p = {oblique.origin[0] + r[0], oblique.origin[1] + r[1], oblique.origin[2] + r[2]};
    }
    for (RefineScheme scheme : {RefineScheme::kLongestEdge, RefineScheme::kPaper}) {
      SCOPED_TRACE(static_cast<int>(scheme));
      RefineOptions o;
      o.scheme = scheme;
      o.epsilon = 0.01;
      o.max_iterations = 4;
      const absl::StatusOr<RefineResult> ra = Refine(a, mesh, o);
      const absl::StatusOr<RefineResult> rb = Refine(*b, rotated, o);
      ASSERT_TRUE(ra.ok()) << ra.status();
      ASSERT_TRUE(rb.ok()) << rb.status();
      ASSERT_GT(ra->mesh.tets.size(), mesh.tets.size());  // it did refine
      ASSERT_EQ(ra->mesh.points.size(), rb->mesh.points.size());
      ASSERT_EQ(ra->mesh.tets, rb->mesh.tets);
      EXPECT_EQ(ra->iterations.size(), rb->iterations.size());
      EXPECT_EQ(ra->stop_reason, rb->stop_reason);
      for (size_t i = 0; i < ra->mesh.points.size(); ++i) {
        const Vec3 r = Apply(oblique.direction, ra->mesh.points[i]);
        for (int axis = 0; axis < 3; ++axis) {
          EXPECT_NEAR(rb->mesh.points[i][axis], oblique.origin[axis] + r[axis], 1e-9)
              << "point " << i;
        }
        EXPECT_NEAR(rb->mesh.values[i], ra->mesh.values[i], 1e-9) << "point " << i;
      }
    }
  }
}

// Found by a CLI sweep: with the grid at 1e7 mm and 1e-4 mm voxels, world points on the grid's
// last samples round to index 9 + 7e-6, beyond the fixed tolerance, so `tetrefine mesh` wrote
// vertices that `refine` refused as outside. The tolerance now covers the rounding of the world
// coordinates, on axis-aligned and oblique grids alike, and still refuses real outside points.
TEST(ObliqueVolume, GridCornersFarFromTheOriginAreInside) {
  for (const bool oblique : {false, true}) {
    for (const double origin : {1e5, 1e7, 1e8, -3e7}) {
      for (const double spacing : {1e-2, 1e-4, 1e-5}) {
        // Beyond 1e12 voxels from the world origin a float64 coordinate no longer resolves a
        // hundredth of a voxel.
        if (std::abs(origin) / spacing > 1e12) continue;
        SCOPED_TRACE(::testing::Message() << oblique << " " << origin << " " << spacing);
        GridGeometry grid;
        grid.dims = {12, 10, 8};
        grid.origin = {origin, origin, -origin};
        grid.spacing = {spacing, 1.5 * spacing, 2 * spacing};
        std::mt19937_64 rng(3);
        if (oblique) grid.direction = testing::RandomRotation(rng);
        absl::StatusOr<Volume> v = Volume::CreateWhole(
            grid, VoxelType::kFloat64, std::vector<std::byte>(12 * 10 * 8 * sizeof(double)));
        ASSERT_TRUE(v.ok()) << v.status();
        for (int corner = 0; corner < 8; ++corner) {
          for (const double inward : {0.0, 0.5}) {
            Vec3 u;
            for (int a = 0; a < 3; ++a) {
              const double last = static_cast<double>(grid.dims[a] - 1);
              u[a] = (corner >> a) & 1 ? last - inward : inward;
            }
            EXPECT_TRUE(v->Contains(v->ContinuousIndex(WorldOfIndex(grid, u)))) << corner;
          }
          // A hundredth of a voxel outside is outside.
          Vec3 out;
          for (int a = 0; a < 3; ++a) {
            out[a] = (corner >> a) & 1 ? static_cast<double>(grid.dims[a] - 1) + 0.01 : -0.01;
          }
          EXPECT_FALSE(v->Contains(v->ContinuousIndex(WorldOfIndex(grid, out)))) << corner;
        }
        for (int a = 0; a < 3; ++a) EXPECT_LT(v->boundary_tolerance()[a], 5e-3);
      }
    }
  }
  // Ordinary grids keep the fixed tolerance but for about 1e-13 of a voxel.
  const Volume ordinary = testing::TestVolume({5, 6, 7});
  for (int a = 0; a < 3; ++a) {
    EXPECT_NEAR(ordinary.boundary_tolerance()[a], Volume::kGridBoundaryTolerance, 1e-12);
  }
}

}  // namespace
}  // namespace tetrefine
