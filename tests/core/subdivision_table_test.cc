#include "core/subdivision_table.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <map>
#include <set>
#include <vector>

namespace tetrefine {
namespace {

TEST(PatternTable, CoversAll64PatternsWithTable1EntryCounts) {
  // Table 1, column NE.
  const std::map<Configuration, int> expected = {
      {Configuration::k0, 1},   {Configuration::k1, 6},   {Configuration::k2a, 12},
      {Configuration::k2b, 3},  {Configuration::k3a, 4},  {Configuration::k3b, 4},
      {Configuration::k3c, 12}, {Configuration::k4a, 12}, {Configuration::k4b, 3},
      {Configuration::k5, 6},   {Configuration::k6, 1}};
  std::map<Configuration, int> counted;
  for (uint32_t p = 0; p < 64; ++p) {
    const PatternEntry& e = PatternTable()[p];
    ++counted[e.configuration];
    // The order maps the canonical pattern onto this one.
    uint32_t mapped = 0;
    const uint32_t canonical = CanonicalPattern(e.configuration);
    for (int k = 0; k < 6; ++k) {
      if (canonical & EdgeBit(k)) {
        mapped |= EdgeBit(EdgeIndex(e.order[kTetEdges[k][0]], e.order[kTetEdges[k][1]]));
      }
    }
    EXPECT_EQ(mapped, p) << "pattern " << p;
    EXPECT_EQ(__builtin_popcount(p), __builtin_popcount(canonical));
  }
  EXPECT_EQ(counted, expected);
}

TEST(PatternTable, Figure13EntryIs3bAtVertex1) {
  // 011001 -> 25 splits edges 01, 12, 13: configuration 3b around v1; the paper's order starts
  // [v1, ...].
  const PatternEntry& e = PatternTable()[25];
  EXPECT_EQ(e.configuration, Configuration::k3b);
  EXPECT_EQ(e.order[0], 1);
}

std::vector<std::array<uint8_t, 4>> SortedChildren(const SubdivisionEntry& e) {
  std::vector<std::array<uint8_t, 4>> out;
  for (int i = 0; i < e.tet_count; ++i) {
    std::array<uint8_t, 4> t = e.tets[i];
    std::sort(t.begin(), t.end());
    out.push_back(t);
  }
  std::sort(out.begin(), out.end());
  return out;
}

TEST(SubdivisionTable, EveryPatternHasEntriesWithTable1CountsAndNDT) {
  const auto& table = SubdivisionTable();
  // Table 1, column NDT: distinct tetrahedrizations of the canonical pattern. Configuration 6 is
  // the exception: the paper counts 1, we count the 3 octahedron diagonals as distinct.
  const std::map<Configuration, size_t> ndt = {
      {Configuration::k0, 1},  {Configuration::k1, 1},  {Configuration::k2a, 2},
      {Configuration::k2b, 1}, {Configuration::k3a, 1}, {Configuration::k3b, 8},
      {Configuration::k3c, 4}, {Configuration::k4a, 4}, {Configuration::k4b, 22},
      {Configuration::k5, 6},  {Configuration::k6, 3}};
  for (int c = 0; c < kNumConfigurations; ++c) {
    const auto config = static_cast<Configuration>(c);
    const uint32_t pattern = CanonicalPattern(config);
    std::set<std::vector<std::array<uint8_t, 4>>> distinct;
    std::set<int> counts;
    for (uint32_t key = pattern; key < kNumSubdivisionKeys; key += 64) {
      const SubdivisionEntry& e = table[key];
      if (!e.valid) continue;
      EXPECT_EQ(e.configuration, config);
      counts.insert(e.tet_count);
      distinct.insert(SortedChildren(e));
    }
    std::set<int> expected_counts = {ConfigurationTetCount(config, false)};
    if (config == Configuration::k3b || config == Configuration::k4b) {
      expected_counts.insert(ConfigurationTetCount(config, true));
    }
    EXPECT_EQ(counts, expected_counts) << ConfigurationName(config);
    EXPECT_EQ(distinct.size(), ndt.at(config)) << ConfigurationName(config);
  }
}

}  // namespace
}  // namespace tetrefine
