#include "client/io/axis_codes.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <random>
#include <string>
#include <string_view>

namespace tetrefine::io {
namespace {

// The direction whose index axis c runs along world axis perm[c] with sign sign[c].
Mat3 SignedPermutation(const std::array<int, 3>& perm, const std::array<int, 3>& sign) {
  Mat3 m{};
  for (int c = 0; c < 3; ++c) m[3 * perm[c] + c] = sign[c];
  return m;
}

// Every one of the 48 signed permutations, with its columns scaled as an affine's spacing
// scales them: the letters name each axis's world direction, and the grid is not oblique.
TEST(IoAxisCodesTest, EverySignedPermutationIsNamedExactly) {
  const char kPositive[3] = {'R', 'A', 'S'};
  const char kNegative[3] = {'L', 'P', 'I'};
  std::array<int, 3> perm = {0, 1, 2};
  int seen = 0;
  do {
    for (int signs = 0; signs < 8; ++signs) {
      const std::array<int, 3> sign = {signs & 1 ? -1 : 1, signs & 2 ? -1 : 1, signs & 4 ? -1 : 1};
      Mat3 m = SignedPermutation(perm, sign);
      const double spacing[3] = {0.5, 3.0, 1.25};
      for (int i = 0; i < 9; ++i) m[i] *= spacing[i % 3];
      std::string expected;
      for (int c = 0; c < 3; ++c) {
        expected += sign[c] > 0 ? kPositive[perm[c]] : kNegative[perm[c]];
      }
      const AxisCodes codes = AxisCodesOf(m);
      EXPECT_EQ(codes.codes, expected);
      EXPECT_TRUE(codes.exact) << expected;
      ++seen;
    }
  } while (std::next_permutation(perm.begin(), perm.end()));
  EXPECT_EQ(seen, 48);
}

// The files shipped in ../shared/data, as nibabel's aff2axcodes names them (checked with
// nibabel 5 on 2026-11-28): the T1 volume's affine runs i to the left, j up and k to the front.
TEST(IoAxisCodesTest, MatchesNibabelOnTheShippedFiles) {
  const Mat3 t1 = {-2.0, 0.0, 0.0, 0.0, 0.0, 3.0, 0.0, 2.0, 0.0};
  EXPECT_EQ(AxisCodesOf(t1).codes, "LSA");
  EXPECT_TRUE(AxisCodesOf(t1).exact);
  // The EPI volume's sform, oblique: closest to LPS.
  const Mat3 epi = {-3.99979, -5.81755e-06, -0.0516361, 0.0239939, -3.25639,
                    -2.90348, -0.0336261,   -2.32291,   4.07027};
  EXPECT_EQ(AxisCodesOf(epi).codes, "LPS");
  EXPECT_FALSE(AxisCodesOf(epi).exact);
}

// A rotation about z: below 45 degrees i stays closest to R; beyond it, to A (and j to L).
TEST(IoAxisCodesTest, RotatedGridsAreObliqueWithTheirClosestAxes) {
  for (double degrees : {10.0, 30.0, 44.0, 46.0, 60.0, 89.0}) {
    const double a = degrees * M_PI / 180.0;
    const Mat3 m = {std::cos(a), -std::sin(a), 0.0, std::sin(a), std::cos(a), 0.0, 0.0, 0.0, 1.0};
    const AxisCodes codes = AxisCodesOf(m);
    EXPECT_FALSE(codes.exact) << degrees;
    EXPECT_EQ(codes.codes, degrees < 45.0 ? "RAS" : "ALS") << degrees;
  }
}

// Scaling columns (an affine's spacing) changes no letter: random rotations, scaled by
// anisotropic spacings up to 20:1. (python/tests/test_adapters.py compares `info` with nibabel
// itself on such grids.)
TEST(IoAxisCodesTest, ColumnLengthsDoNotChangeTheLetters) {
  std::mt19937_64 rng(7);
  std::normal_distribution<double> normal;
  std::uniform_real_distribution<double> scale(0.1, 2.0);
  for (int trial = 0; trial < 2000; ++trial) {
    // A random rotation: Gram-Schmidt on three Gaussian columns.
    std::array<std::array<double, 3>, 3> col;
    for (auto& c : col) {
      for (double& x : c) x = normal(rng);
    }
    for (int c = 0; c < 3; ++c) {
      for (int p = 0; p < c; ++p) {
        double dot = 0.0;
        for (int r = 0; r < 3; ++r) dot += col[c][r] * col[p][r];
        for (int r = 0; r < 3; ++r) col[c][r] -= dot * col[p][r];
      }
      double norm = 0.0;
      for (int r = 0; r < 3; ++r) norm += col[c][r] * col[c][r];
      for (int r = 0; r < 3; ++r) col[c][r] /= std::sqrt(norm);
    }
    Mat3 unit, scaled;
    for (int c = 0; c < 3; ++c) {
      const double s = scale(rng);
      for (int r = 0; r < 3; ++r) {
        unit[3 * r + c] = col[c][r];
        scaled[3 * r + c] = s * col[c][r];
      }
    }
    const AxisCodes a = AxisCodesOf(unit);
    EXPECT_EQ(a.codes, AxisCodesOf(scaled).codes) << trial;
    // Each world axis named once.
    std::string axes;
    for (char ch : a.codes) {
      const size_t negative = std::string_view("LPI").find(ch);
      axes += negative == std::string_view::npos ? ch : "RAS"[negative];
    }
    std::sort(axes.begin(), axes.end());
    EXPECT_EQ(axes, "ARS") << a.codes;
  }
}

TEST(IoAxisCodesTest, WordsOfTheLetters) {
  EXPECT_STREQ(AxisCodeWord('L'), "left");
  EXPECT_STREQ(AxisCodeWord('S'), "superior");
  EXPECT_STREQ(AxisCodeWord('x'), "?");
}

}  // namespace
}  // namespace tetrefine::io
