// The other tilings of each subdivision key: that they tile every tet (not only the reference tet
// they were found on), keep its faces, and that the choice among them depends on geometry only.
#include "core/alternative_tilings.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <map>
#include <numeric>
#include <random>
#include <set>
#include <vector>

#include "core/mesh.h"
#include "core/quality.h"
#include "core/refine_state.h"
#include "core/tet_topology.h"
#include "core/tiling_check.h"
#include "core/vec3_ops.h"
#include "tests/support/geometry.h"

namespace tetrefine {
namespace {

using Triangle = std::array<int, 3>;

// The faces used by exactly one child: the tiling's boundary, as sorted local triangles.
std::set<Triangle> BoundaryOf(const SubdivisionEntry& e) {
  std::map<Triangle, int> uses;
  for (int i = 0; i < e.tet_count; ++i) {
    for (int skip = 0; skip < 4; ++skip) {
      Triangle f{};
      int k = 0;
      for (int j = 0; j < 4; ++j) {
        if (j != skip) f[k++] = e.tets[i][j];
      }
      std::sort(f.begin(), f.end());
      ++uses[f];
    }
  }
  std::set<Triangle> out;
  for (const auto& [f, n] : uses) {
    if (n == 1) out.insert(f);
  }
  return out;
}

std::array<Vec3, 10> TenPoints(const std::array<Vec3, 4>& c) {
  std::array<Vec3, 10> p{};
  for (int i = 0; i < 4; ++i) p[i] = c[i];
  for (int e = 0; e < 6; ++e)
    p[4 + e] = refine_internal::Midpoint(c[kTetEdges[e][0]], c[kTetEdges[e][1]]);
  return p;
}

double Worst(const SubdivisionEntry& e, const std::array<Vec3, 4>& corners) {
  const auto local = LocalPoints(corners, e);
  double worst = 1.0;
  for (int i = 0; i < e.tet_count; ++i) {
    const auto& c = e.tets[i];
    worst = std::min(worst, MeanRatio(local[c[0]], local[c[1]], local[c[2]], local[c[3]]));
  }
  return worst;
}

// The children of the chosen tiling as sets of points: what a renumbering must not change.
std::set<std::array<Vec3, 4>> ChosenChildren(const std::array<Vec3, 4>& corners, uint32_t pattern) {
  const uint32_t key = SubdivisionKey(pattern, TenPoints(corners));
  const SubdivisionEntry& e = TilingEntry(BestTiling(key, corners));
  const auto local = LocalPoints(corners, e);
  std::set<std::array<Vec3, 4>> out;
  for (int i = 0; i < e.tet_count; ++i) {
    std::array<Vec3, 4> c = {local[e.tets[i][0]], local[e.tets[i][1]], local[e.tets[i][2]],
                             local[e.tets[i][3]]};
    std::sort(c.begin(), c.end(), LexLess);
    out.insert(c);
  }
  return out;
}

TEST(AlternativeTilings, CountsPerConfiguration) {
  // What the enumeration finds (2026-11-25): keys with 1 and with 2 other tilings, per
  // configuration. Configurations 3c and 4a are those the guard flagged most (docs/schemes.md).
  std::map<Configuration, std::array<int, 3>> keys;
  const auto& table = SubdivisionTable();
  const auto& alternatives = AlternativeTilingTable();
  for (uint32_t key = 0; key < kNumSubdivisionKeys; ++key) {
    if (!table[key].valid) {
      EXPECT_EQ(alternatives[key].count, 0) << key;
      continue;
    }
    if (table[key].steiner) {
      EXPECT_EQ(alternatives[key].count, 0) << key;
    }
    ++keys[table[key].configuration][alternatives[key].count];
  }
  for (Configuration c : {Configuration::k0, Configuration::k1, Configuration::k2a,
                          Configuration::k2b, Configuration::k3a, Configuration::k3b}) {
    EXPECT_EQ(keys[c][1] + keys[c][2], 0) << ConfigurationName(c);
  }
  EXPECT_EQ(keys[Configuration::k3c][1], 12);
  EXPECT_EQ(keys[Configuration::k4a][1], 12);
  EXPECT_EQ(keys[Configuration::k4b][1], 24);
  EXPECT_EQ(keys[Configuration::k5][1], 24);
  EXPECT_EQ(keys[Configuration::k6][2], 3);
}

TEST(AlternativeTilings, TileEveryTetWithTheTablesFaces) {
  // Found on one reference tet; valid on every tet because orientation and containment are
  // affine invariants. Checked here on random tets of every shape the tests draw.
  const auto& table = SubdivisionTable();
  const auto& alternatives = AlternativeTilingTable();
  for (uint64_t seed : testing::Seeds(3)) {
    SCOPED_TRACE(::testing::Message() << "seed " << seed);
    std::mt19937_64 rng(seed);
    for (int trial = 0; trial < 20; ++trial) {
      const std::array<Vec3, 4> corners = testing::RandomTet(rng, 0.02);
      for (uint32_t key = 0; key < kNumSubdivisionKeys; ++key) {
        const AlternativeTilings& alt = alternatives[key];
        if (alt.count == 0) continue;
        const std::set<Triangle> faces = BoundaryOf(table[key]);
        const std::vector<Triangle> boundary(faces.begin(), faces.end());
        for (int i = 0; i < alt.count; ++i) {
          const SubdivisionEntry& e = alt.entries[i];
          ASSERT_TRUE(e.valid);
          EXPECT_FALSE(e.steiner);
          EXPECT_EQ(e.configuration, table[key].configuration);
          EXPECT_LE(e.tet_count, table[key].tet_count) << key;
          EXPECT_GE(e.tet_count, table[key].tet_count - 1) << key;
          EXPECT_EQ(BoundaryOf(e), faces) << key;
          const auto local = LocalPoints(corners, e);
          std::vector<std::array<int, 4>> tets;
          for (int c = 0; c < e.tet_count; ++c) {
            tets.push_back({e.tets[c][0], e.tets[c][1], e.tets[c][2], e.tets[c][3]});
          }
          std::string why;
          EXPECT_TRUE(IsTiling(tets, boundary, local, &why)) << "key " << key << ": " << why;
        }
      }
    }
  }
}

TEST(AlternativeTilings, BestTilingHasTheBestWorstChild) {
  std::mt19937_64 rng(20261125);
  int chose_other = 0;
  for (int trial = 0; trial < 300; ++trial) {
    const std::array<Vec3, 4> corners = testing::RandomTet(rng, 0.2);
    for (uint32_t pattern = 1; pattern < 64; ++pattern) {
      const uint32_t key = SubdivisionKey(pattern, TenPoints(corners));
      const uint32_t best = BestTiling(key, corners);
      ASSERT_EQ(best & (kNumSubdivisionKeys - 1), key);
      const double chosen = Worst(TilingEntry(best), corners);
      EXPECT_GE(chosen, Worst(SubdivisionTable()[key], corners) * (1 - 1e-12));
      const AlternativeTilings& alt = AlternativeTilingTable()[key];
      for (int i = 0; i < alt.count; ++i) {
        EXPECT_GE(chosen, Worst(alt.entries[i], corners) * (1 - 1e-12));
      }
      chose_other += (best >> kTilingShift) != 0;
    }
  }
  // Not a formality: on random tets another tiling often wins.
  EXPECT_GT(chose_other, 300);
}

// Every renumbering of a tet's corners (the 24 permutations) gives the same children, as point
// sets: on random tets, and on the corner tets of a grid cell, whose right angles and equal
// edges make exact ties between tilings.
void ExpectSameChildrenUnderEveryNumbering(std::array<Vec3, 4> corners) {
  if (SignedVolume6(corners[0], corners[1], corners[2], corners[3]) < 0) {
    std::swap(corners[2], corners[3]);
  }
  for (uint32_t pattern = 1; pattern < 64; ++pattern) {
    const auto expected = ChosenChildren(corners, pattern);
    std::array<int, 4> perm = {0, 1, 2, 3};
    while (std::next_permutation(perm.begin(), perm.end())) {
      std::array<Vec3, 4> c{};
      for (int i = 0; i < 4; ++i) c[i] = corners[perm[i]];
      if (SignedVolume6(c[0], c[1], c[2], c[3]) < 0) continue;  // tets are positively oriented
      uint32_t p = 0;
      for (int e = 0; e < 6; ++e) {
        const int a = perm[kTetEdges[e][0]], b = perm[kTetEdges[e][1]];
        if ((pattern & EdgeBit(EdgeIndex(a, b))) != 0) p |= EdgeBit(e);
      }
      EXPECT_EQ(ChosenChildren(c, p), expected) << "pattern " << pattern;
    }
  }
}

TEST(AlternativeTilings, ChoiceIgnoresTheNumbering) {
  std::mt19937_64 rng(7);
  for (int trial = 0; trial < 20; ++trial) {
    ExpectSameChildrenUnderEveryNumbering(testing::RandomTet(rng, 0.2));
  }
  // A grid cell's corner tet and its middle tet (the five-tet split of a unit cube).
  ExpectSameChildrenUnderEveryNumbering({{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}}});
  ExpectSameChildrenUnderEveryNumbering({{{1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {1, 1, 1}}});
  ExpectSameChildrenUnderEveryNumbering({{{0, 0, 0}, {2, 0, 0}, {0, 1, 0}, {0, 0, 1}}});
}

}  // namespace
}  // namespace tetrefine
