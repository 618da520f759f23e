// The mean-ratio comparisons without a cube root (MeanRatioBelow, MinMeanRatio) give exactly the
// answers MeanRatioOf's bits give: on random tets of every scale, on thresholds one unit in the
// last place either side of a tet's own value, and on degenerate tets. MeanRatioAsFloat, with its
// fast cube root, gives the float MeanRatioOf's bits round to.

#include "core/quality.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstdio>
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

// FastCbrt against long double's cbrtl, over the three exponent residues (the estimate from the
// bits depends on the exponent mod 3 and the mantissa) at magnitudes a mean ratio's argument
// takes, and across each binade's mantissas.
TEST(QualityTest, FastCbrtIsWithinItsErrorBound) {
  std::mt19937_64 rng(14);
  std::uniform_real_distribution<double> mantissa(1.0, 2.0);
  double worst = 0.0;
  for (int exponent = -600; exponent <= 600; exponent += 1) {
    for (int i = 0; i < 400; ++i) {
      const double x = std::ldexp(i == 0 ? 1.0 : mantissa(rng), exponent);
      const long double exact = cbrtl(static_cast<long double>(x));
      const double error = static_cast<double>(
          fabsl((static_cast<long double>(quality_internal::FastCbrt(x)) - exact) / exact));
      worst = std::max(worst, error);
    }
  }
  EXPECT_LT(worst, quality_internal::kFastCbrtError);
  // The bound leaves room: the code's margin is four times it.
  EXPECT_GT(worst, 0.0);
  std::printf("FastCbrt's largest relative error: %.3g\n", worst);
}

// MeanRatioAsFloat gives the float MeanRatioOf's value rounds to: on random tets of every scale,
// and on parts whose value lies within a few units in the last place of the midpoint between two
// floats, where the fast cube root cannot decide and the exact path must.
TEST(QualityTest, AsFloatIsTheRoundedMeanRatioEvenNearFloatMidpoints) {
  std::mt19937_64 rng(15);
  for (double scale : {1e-150, 1e-40, 1e-3, 1.0, 250.0, 1e40, 1e150}) {
    for (int i = 0; i < 20000; ++i) {
      const MeanRatioParts parts = PartsOf(Scaled(testing::RandomTet(rng, 0.0), scale));
      // Bits: at 1e150 the parts overflow and both are NaN.
      ASSERT_EQ(std::bit_cast<uint32_t>(MeanRatioAsFloat(parts)),
                std::bit_cast<uint32_t>(static_cast<float>(MeanRatioOf(parts))))
          << "scale " << scale;
    }
  }
  // sum_l2 = 12 makes the value cbrt(9 v^2): v = sqrt(m^3 / 9) puts it at a chosen m.
  std::uniform_real_distribution<float> quality(1e-6f, 1.0f);
  int at_midpoint = 0;
  for (int i = 0; i < 20000; ++i) {
    const float f = quality(rng);
    const double midpoint = (static_cast<double>(f) + std::nextafter(f, 2.0f)) / 2.0;
    for (double m : {midpoint, std::nextafter(midpoint, 0.0), std::nextafter(midpoint, 2.0),
                     midpoint * (1 + 1e-14), midpoint * (1 - 1e-14)}) {
      const MeanRatioParts parts{std::sqrt(m * m * m / 9.0), 12.0};
      const double exact = MeanRatioOf(parts);
      at_midpoint += std::abs(exact - midpoint) < 1e-12 * midpoint;
      ASSERT_EQ(MeanRatioAsFloat(parts), static_cast<float>(exact)) << "m " << m;
    }
  }
  EXPECT_GT(at_midpoint, 5 * 20000 * 9 / 10);  // the constructed values did land there
  // Degenerate and tiny parts take the exact path.
  for (const MeanRatioParts& parts :
       {MeanRatioParts{0.0, 3.0}, MeanRatioParts{0.0, 0.0}, MeanRatioParts{1e-200, 1e-100},
        MeanRatioParts{1e200, 1e95}}) {
    EXPECT_EQ(MeanRatioAsFloat(parts), static_cast<float>(MeanRatioOf(parts)));
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
