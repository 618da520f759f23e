// IsTiling, the check the subdivision table is built and verified with: it accepts exactly the
// sets of tets that fill the region bounded by the given triangles once, and names what is wrong
// otherwise.

#include "core/tiling_check.h"

#include <array>
#include <string>
#include <vector>

#include "gmock/gmock.h"
#include "gtest/gtest.h"

namespace tetrefine {
namespace {

using ::testing::HasSubstr;
using TileTet = std::array<int, 4>;
using TileFace = std::array<int, 3>;

// A positively oriented tet (0 1 2 3), its centroid (4) and a point (5) beyond face (0 1 2) on
// the side of corner 3.
const std::vector<Vec3> kPoints = {{0, 0, 0}, {1, 0, 0},          {0, 1, 0},
                                   {0, 0, 1}, {0.25, 0.25, 0.25}, {0.2, 0.2, 0.5}};
const std::vector<TileFace> kTetFaces = {{1, 2, 3}, {0, 2, 3}, {0, 1, 3}, {0, 1, 2}};

// The tet split at its centroid: the four corners' opposite faces each coned to point 4.
std::vector<TileTet> CentroidSplit() {
  return {{4, 1, 2, 3}, {0, 4, 2, 3}, {0, 1, 4, 3}, {0, 1, 2, 4}};
}

bool Tiles(const std::vector<TileTet>& tets, const std::vector<TileFace>& boundary,
           std::string* why = nullptr) {
  return IsTiling(tets, boundary, kPoints, why);
}

TEST(IsTiling, TheWholeTetAndItsCentroidSplitTileIt) {
  std::string why;
  EXPECT_TRUE(Tiles({{0, 1, 2, 3}}, kTetFaces, &why)) << why;
  EXPECT_TRUE(Tiles(CentroidSplit(), kTetFaces, &why)) << why;
}

TEST(IsTiling, AMissingChildLeavesABoundaryTriangleUncovered) {
  for (size_t drop = 0; drop < 4; ++drop) {
    std::vector<TileTet> tets = CentroidSplit();
    tets.erase(tets.begin() + static_cast<long>(drop));
    std::string why;
    EXPECT_FALSE(Tiles(tets, kTetFaces, &why)) << "without child " << drop;
    EXPECT_THAT(why, HasSubstr("boundary triangle")) << why;
    EXPECT_FALSE(Tiles(tets, kTetFaces)) << "the verdict does not depend on asking why";
  }
}

TEST(IsTiling, AChildListedTwiceCoversItsBoundaryTriangleTwice) {
  std::vector<TileTet> tets = CentroidSplit();
  tets.push_back(tets[1]);
  std::string why;
  EXPECT_FALSE(Tiles(tets, kTetFaces, &why));
  EXPECT_THAT(why, HasSubstr("boundary triangle (0 2 3) is not the face of exactly one tet"))
      << why;
}

TEST(IsTiling, AnInvertedChildHasNoPositiveVolume) {
  std::vector<TileTet> tets = CentroidSplit();
  std::swap(tets[2][0], tets[2][1]);
  std::string why;
  EXPECT_FALSE(Tiles(tets, kTetFaces, &why));
  EXPECT_THAT(why, HasSubstr("tet 2 (1 0 4 3) has no positive volume")) << why;
}

TEST(IsTiling, ABoundaryTriangleListedTwiceIsRefused) {
  std::vector<TileFace> boundary = kTetFaces;
  boundary.push_back({3, 2, 1});
  std::string why;
  EXPECT_FALSE(Tiles({{0, 1, 2, 3}}, boundary, &why));
  EXPECT_THAT(why, HasSubstr("listed twice")) << why;
}

TEST(IsTiling, AFaceOnNoBoundaryTriangleThatOneTetHasIsAHole) {
  // The tet alone, told its boundary lacks face (0 1 2) and has a triangle it does not have.
  std::vector<TileFace> boundary = {{1, 2, 3}, {0, 2, 3}, {0, 1, 3}, {0, 1, 5}};
  std::string why;
  EXPECT_FALSE(Tiles({{0, 1, 2, 3}}, boundary, &why));
  EXPECT_THAT(why, HasSubstr("(0 1 2) is on no boundary triangle")) << why;
}

TEST(IsTiling, TwoTetsOnTheSameSideOfTheirSharedFaceOverlap) {
  // (0 1 2 3) and (0 1 2 5): point 5 is on corner 3's side of (0 1 2), so both lie above it and
  // the "interior" face (0 1 2) is not between them.
  const std::vector<TileTet> tets = {{0, 1, 2, 3}, {0, 1, 2, 5}};
  const std::vector<TileFace> boundary = {{1, 2, 3}, {0, 2, 3}, {0, 1, 3},
                                          {1, 2, 5}, {0, 2, 5}, {0, 1, 5}};
  std::string why;
  EXPECT_FALSE(Tiles(tets, boundary, &why));
  EXPECT_THAT(why, HasSubstr("the two tets at face (0 1 2) overlap")) << why;
}

}  // namespace
}  // namespace tetrefine
