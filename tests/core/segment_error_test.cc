// The exact maximum discrepancy along a segment against dense sampling, on random volumes and
// segments of every length from inside one cell to across the grid.
#include "core/segment_error.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "tests/support/geometry.h"

namespace tetrefine {
namespace {

GridGeometry SmallGrid() {
  GridGeometry g;
  g.dims = {7, 6, 5};
  g.spacing = {1.5, 2.0, 0.75};
  g.origin = {-3.0, 1.0, 2.0};
  return g;
}

Volume RandomVolume(std::mt19937_64& rng, const GridGeometry& g) {
  std::uniform_real_distribution<double> u(-50.0, 50.0);
  std::vector<double> v(g.dims[0] * g.dims[1] * g.dims[2]);
  for (double& x : v) x = u(rng);
  return *Volume::FromDoubles(g, v);
}

Vec3 RandomPoint(std::mt19937_64& rng, const GridGeometry& g) {
  Vec3 p;
  for (int a = 0; a < 3; ++a) {
    std::uniform_real_distribution<double> u(0.0, (g.dims[a] - 1) * g.spacing[a]);
    p[a] = g.origin[a] + u(rng);
  }
  return p;
}

double SampledMax(const Volume& v, const Vec3& a, const Vec3& b, double va, double vb, int n) {
  double best = 0.0;
  for (int i = 0; i <= n; ++i) {
    const double t = static_cast<double>(i) / n;
    const Vec3 p = {a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1]), a[2] + t * (b[2] - a[2])};
    best = std::max(best, std::abs(v.Sample(p) - ((1 - t) * va + t * vb)));
  }
  return best;
}

TEST(MaxSegmentDiscrepancy, BoundsAndMatchesDenseSampling) {
  for (uint64_t seed : testing::Seeds(20)) {
    SCOPED_TRACE(::testing::Message() << "seed " << seed);
    std::mt19937_64 rng(seed);
    const GridGeometry g = SmallGrid();
    const Volume volume = RandomVolume(rng, g);
    for (int s = 0; s < 50; ++s) {
      const Vec3 a = RandomPoint(rng, g);
      Vec3 b = RandomPoint(rng, g);
      if (s % 2 == 0) {  // short segments, often inside one cell
        for (int k = 0; k < 3; ++k) b[k] = a[k] + 0.1 * (b[k] - a[k]);
      }
      const double va = volume.Sample(a), vb = volume.Sample(b);
      const double exact = MaxSegmentDiscrepancy(volume, a, b, va, vb, false);
      const double sampled = SampledMax(volume, a, b, va, vb, 20000);
      // Never below any sample; above the densest sampling only by what 20,000 steps miss.
      EXPECT_GE(exact, sampled - 1e-9);
      EXPECT_LE(exact, sampled + 1e-3 * (1.0 + sampled));
    }
  }
}

TEST(MaxSegmentDiscrepancy, SameBitsWhicheverEndComesFirst) {
  std::mt19937_64 rng(7);
  const GridGeometry g = SmallGrid();
  const Volume volume = RandomVolume(rng, g);
  for (int s = 0; s < 200; ++s) {
    const Vec3 a = RandomPoint(rng, g), b = RandomPoint(rng, g);
    const double va = volume.Sample(a), vb = volume.Sample(b);
    EXPECT_EQ(MaxSegmentDiscrepancy(volume, a, b, va, vb, false),
              MaxSegmentDiscrepancy(volume, b, a, vb, va, false));
  }
}

TEST(MaxSegmentDiscrepancy, ZeroOnAnAffineField) {
  const GridGeometry g = SmallGrid();
  const Volume volume = testing::AnalyticVolume(
      g, [](const Vec3& p) { return 3.0 * p[0] - 2.0 * p[1] + 0.5 * p[2] + 7.0; });
  std::mt19937_64 rng(3);
  for (int s = 0; s < 100; ++s) {
    const Vec3 a = RandomPoint(rng, g), b = RandomPoint(rng, g);
    EXPECT_NEAR(MaxSegmentDiscrepancy(volume, a, b, volume.Sample(a), volume.Sample(b), false), 0.0,
                1e-9);
  }
}

// A kink the midpoint misses: a segment crossing one voxel face off-centre, with the values at
// its ends, has its worst point at the face, not at the midpoint.
TEST(MaxSegmentDiscrepancy, FindsTheKinkAtACellFace) {
  GridGeometry g;
  g.dims = {4, 2, 2};
  g.origin = {0, 0, 0};
  g.spacing = {1, 1, 1};
  // Value 0 except the plane x = 1, which is 1: a tent along x.
  const Volume volume =
      testing::AnalyticVolume(g, [](const Vec3& p) { return p[0] == 1.0 ? 1.0 : 0.0; });
  const Vec3 a = {0.0, 0.5, 0.5}, b = {3.0, 0.5, 0.5};
  // Ends are 0; the field peaks at x = 1 with value 1; the midpoint x = 1.5 has 0.5.
  EXPECT_DOUBLE_EQ(MaxSegmentDiscrepancy(volume, a, b, 0.0, 0.0, false), 1.0);
}

}  // namespace
}  // namespace tetrefine
