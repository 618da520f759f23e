// The quality the longest-edge guard's floor is relative to (RefineOptions::quality_reference):
// the input's worst tet by default, the same bits whatever the order of corners and tets, and
// what a caller refining in pieces passes explicitly.

#include <algorithm>
#include <array>
#include <random>
#include <vector>

#include "core/mesh.h"
#include "core/quality.h"
#include "core/refine.h"
#include "core/vec3_ops.h"
#include "gtest/gtest.h"
#include "tests/support/geometry.h"
#include "tests/support/pinned_cases.h"

namespace tetrefine {
namespace {

TEST(QualityReferenceTest, IsTheWorstTetWhateverTheOrderOfCornersAndTets) {
  EXPECT_EQ(QualityReference({}, {}), 1.0);
  for (uint64_t seed : testing::Seeds(5)) {
    std::mt19937_64 rng(seed);
    std::vector<Vec3> points;
    std::vector<Tet> tets;
    for (uint32_t t = 0; t < 300; ++t) {
      const std::array<Vec3, 4> c = testing::RandomTet(rng, 0.01);
      for (const Vec3& p : c) points.push_back(p);
      tets.push_back({4 * t, 4 * t + 1, 4 * t + 2, 4 * t + 3});
    }
    const double reference = QualityReference(points, tets);
    double worst = 1.0;
    for (const Tet& t : tets) {
      worst = std::min(worst, MeanRatio(points[t[0]], points[t[1]], points[t[2]], points[t[3]]));
    }
    EXPECT_NEAR(reference, worst, 1e-12 * worst) << "seed " << seed;
    // Every tet's corners in another order (half of them inside out), the tets shuffled.
    std::vector<Tet> shuffled = tets;
    for (Tet& t : shuffled) std::shuffle(t.begin(), t.end(), rng);
    std::shuffle(shuffled.begin(), shuffled.end(), rng);
    EXPECT_EQ(QualityReference(points, shuffled), reference) << "seed " << seed;
  }
}

// The plain minimum over every tet, each measured with its corners sorted (what
// QualityReference computes, without its filter on the cube).
double PlainReference(const std::vector<Vec3>& points, const std::vector<Tet>& tets) {
  double worst = 1.0;
  for (const Tet& t : tets) {
    std::array<Vec3, 4> c = {points[t[0]], points[t[1]], points[t[2]], points[t[3]]};
    std::sort(c.begin(), c.end(), LexLess);
    worst = std::min(worst, MeanRatio(c[0], c[1], c[2], c[3]));
  }
  return worst;
}

// The filter that skips the cube root must never change the bits: on meshes of congruent tets
// (exact ties in shape, rounding that differs from copy to copy), jittered ones (near ties), and
// random ones, at scales from micrometres to kilometres and beyond the filter's safe range.
TEST(QualityReferenceTest, EqualsThePlainMinimumToTheBit) {
  for (uint64_t seed : testing::Seeds(8)) {
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> jitter(-1e-13, 1e-13);
    for (double scale : {1e-6, 1.0, 1e3, 1e50}) {
      Mesh m = testing::FiveTetMesh({0, 0, 0}, {scale, 1.3 * scale, 0.7 * scale}, {9, 7, 8});
      EXPECT_EQ(QualityReference(m.points, m.tets), PlainReference(m.points, m.tets))
          << "congruent, seed " << seed << " scale " << scale;
      for (Vec3& p : m.points) {
        for (double& x : p) x += jitter(rng) * scale;
      }
      EXPECT_EQ(QualityReference(m.points, m.tets), PlainReference(m.points, m.tets))
          << "jittered, seed " << seed << " scale " << scale;
      std::vector<Vec3> points;
      std::vector<Tet> tets;
      for (uint32_t t = 0; t < 2000; ++t) {
        for (const Vec3& p : testing::RandomTet(rng, 0.01)) {
          points.push_back({p[0] * scale, p[1] * scale, p[2] * scale});
        }
        tets.push_back({4 * t, 4 * t + 1, 4 * t + 2, 4 * t + 3});
      }
      EXPECT_EQ(QualityReference(points, tets), PlainReference(points, tets))
          << "random, seed " << seed << " scale " << scale;
    }
  }
}

bool SameMesh(const RefineResult& a, const RefineResult& b) {
  return a.mesh.points == b.mesh.points && a.mesh.tets == b.mesh.tets;
}

// Unset, the reference is the input's worst tet: passing that value changes nothing. A much
// lower one (no floor in effect) changes the mesh on a pinned case, so the floor acts there.
TEST(QualityReferenceTest, DefaultsToTheInputsWorstTetAndIsUsed) {
  int floor_acted = 0;
  for (const testing::PinnedCase& c : testing::PinnedCases()) {
    SCOPED_TRACE(c.name);
    RefineOptions o;
    o.scheme = RefineScheme::kLongestEdge;
    o.epsilon = 0.05;
    o.max_iterations = 32;
    o.lattice_n = 0;
    const auto unset = Refine(c.volume, c.mesh, o);
    ASSERT_TRUE(unset.ok()) << unset.status();
    o.quality_reference = QualityReference(c.mesh.points, c.mesh.tets);
    const auto same = Refine(c.volume, c.mesh, o);
    ASSERT_TRUE(same.ok()) << same.status();
    EXPECT_TRUE(SameMesh(*unset, *same));
    o.quality_reference = 1e-6;
    const auto without_floor = Refine(c.volume, c.mesh, o);
    ASSERT_TRUE(without_floor.ok()) << without_floor.status();
    if (!SameMesh(*unset, *without_floor)) ++floor_acted;
  }
  EXPECT_GT(floor_acted, 0);
}

}  // namespace
}  // namespace tetrefine
