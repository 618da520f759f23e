// The mean-ratio comparisons without a cube root (MeanRatioBelow, MinMeanRatio) give exactly the
// answers MeanRatioOf's bits give: on random tets of every scale, on thresholds one unit in the
// last place either side of a tet's own value, and on degenerate tets.

#include "core/quality.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include "gtest/gtest.h"
#include "tests/support/geometry.h"

namespace tetrefine {
namespace {

std::array<Vec3, 4> Scaled(std::array<Vec3, 4> p, double scale) {
  for (Vec3& v : p) {
    for (double& x : v) x *= scale;
  }
  return p;
}

MeanRatioParts PartsOf(const std::array<Vec3, 4>& p) {
  return MeanRatioPartsOf(p[0], p[1], p[2], p[3]);
}

TEST(QualityTest, PartsGiveMeanRatiosBits) {
  std::mt19937_64 rng(11);
  for (int i = 0; i < 2000; ++i) {
    const auto p = testing::RandomTet(rng, 0.0);
    EXPECT_EQ(MeanRatioOf(PartsOf(p)), MeanRatio(p[0], p[1], p[2], p[3]));
  }
}

TEST(QualityTest, BelowIsExactAtEveryScaleAndAtTheThreshold) {
  std::mt19937_64 rng(12);
  const double inf = std::numeric_limits<double>::infinity();
  int near = 0;
  for (double scale : {1e-150, 1e-40, 1e-3, 1.0, 250.0, 1e40, 1e150}) {
    for (int i = 0; i < 500; ++i) {
      const MeanRatioParts parts = PartsOf(Scaled(testing::RandomTet(rng, 0.0), scale));
      const double q = MeanRatioOf(parts);
      // The tet's own value and its neighbours: the cases a filter gets wrong if it is not exact.
      for (double t : {q, std::nextafter(q, inf), std::nextafter(q, -inf), q * (1 + 1e-13),
                       q * (1 - 1e-13), 0.6 * q, q / 0.6, 0.0, -1.0, 2.0}) {
        EXPECT_EQ(MeanRatioBelow(parts, t), q < t) << "scale " << scale << ", q " << q;
        ++near;
      }
    }
  }
  EXPECT_EQ(near, 7 * 500 * 10);
}

TEST(QualityTest, MinIsExactOnNearTiesAndDegenerateTets) {
  std::mt19937_64 rng(13);
  std::uniform_int_distribution<int> count_of(1, 11);
  for (int i = 0; i < 3000; ++i) {
    const int count = count_of(rng);
    std::vector<MeanRatioParts> parts;
    const auto base = testing::RandomTet(rng, 0.0);
    for (int k = 0; k < count; ++k) {
      std::array<Vec3, 4> p = base;
      // Copies of one tet moved by a few units in the last place (values within the filter's
      // margin of each other), others random, one in eight flat.
      if (k % 3 == 0) {
        p = testing::RandomTet(rng, 0.0);
      } else {
        p[0][0] = std::nextafter(p[0][0], k % 2 == 0 ? 10.0 : -10.0);
      }
      if (k % 8 == 7) p[3] = p[0];
      parts.push_back(PartsOf(p));
    }
    double want = MeanRatioOf(parts[0]);
    for (const auto& q : parts) want = std::min(want, MeanRatioOf(q));
    EXPECT_EQ(MinMeanRatio(parts.data(), count), want) << "case " << i;
  }
}

}  // namespace
}  // namespace tetrefine
