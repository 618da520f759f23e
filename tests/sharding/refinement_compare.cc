#include "tests/sharding/refinement_compare.h"

#include <algorithm>
#include <array>
#include <bit>
#include <cstdint>
#include <vector>

#include "gtest/gtest.h"

namespace tetrefine::testing {
namespace {

using VertexKey = std::array<uint64_t, 4>;  // x, y, z, value bits
using TetKey = std::array<uint64_t, 14>;    // 4 corners x (x, y, z), iteration, quality bits

uint64_t Bits(double v) { return std::bit_cast<uint64_t>(v); }

std::vector<VertexKey> SortedVertices(const Mesh& m) {
  std::vector<VertexKey> keys;
  for (size_t i = 0; i < m.points.size(); ++i) {
    keys.push_back(
        {Bits(m.points[i][0]), Bits(m.points[i][1]), Bits(m.points[i][2]), Bits(m.values[i])});
  }
  std::sort(keys.begin(), keys.end());
  return keys;
}

std::vector<TetKey> SortedTets(const RefineResult& r) {
  std::vector<TetKey> keys;
  for (size_t t = 0; t < r.mesh.tets.size(); ++t) {
    TetKey k{};
    for (int c = 0; c < 4; ++c) {
      for (int a = 0; a < 3; ++a) k[3 * c + a] = Bits(r.mesh.points[r.mesh.tets[t][c]][a]);
    }
    k[12] = static_cast<uint64_t>(static_cast<uint32_t>(r.tet_iteration[t]));
    k[13] = std::bit_cast<uint32_t>(r.tet_quality[t]);
    keys.push_back(k);
  }
  std::sort(keys.begin(), keys.end());
  return keys;
}

template <typename Key>
void ExpectSameKeys(const std::vector<Key>& expected, const std::vector<Key>& actual,
                    const char* what) {
  ASSERT_EQ(expected.size(), actual.size()) << what;
  const auto [e, a] = std::mismatch(expected.begin(), expected.end(), actual.begin());
  EXPECT_TRUE(e == expected.end()) << what << ": first difference at sorted index "
                                   << (e - expected.begin()) << " of " << expected.size();
}

}  // namespace

bool SameTets(const RefineResult& a, const RefineResult& b) {
  return SortedTets(a) == SortedTets(b);
}

void ExpectSameRefinement(const Mesh& input, const RefineResult& unsharded,
                          const RefineResult& sharded, bool whole_mesh_statistics) {
  ASSERT_EQ(sharded.mesh.values.size(), sharded.mesh.points.size());
  ASSERT_EQ(sharded.tet_iteration.size(), sharded.mesh.tets.size());
  ASSERT_EQ(sharded.tet_quality.size(), sharded.mesh.tets.size());
  const std::vector<VertexKey> vertices = SortedVertices(sharded.mesh);
  for (size_t i = 1; i < vertices.size(); ++i) {
    ASSERT_FALSE(vertices[i][0] == vertices[i - 1][0] && vertices[i][1] == vertices[i - 1][1] &&
                 vertices[i][2] == vertices[i - 1][2])
        << "two merged vertices share a position: the merge missed a shared vertex";
  }
  ExpectSameKeys(SortedVertices(unsharded.mesh), vertices, "vertices");
  ExpectSameKeys(SortedTets(unsharded), SortedTets(sharded), "tets");
  ASSERT_GE(sharded.mesh.points.size(), input.points.size());
  for (size_t i = 0; i < input.points.size(); ++i) {
    ASSERT_EQ(sharded.mesh.points[i], input.points[i]) << "input vertex " << i << " moved";
    ASSERT_EQ(Bits(sharded.mesh.values[i]), Bits(unsharded.mesh.values[i])) << "vertex " << i;
  }

  EXPECT_EQ(sharded.stop_reason, unsharded.stop_reason)
      << StopReasonName(sharded.stop_reason) << " vs " << StopReasonName(unsharded.stop_reason);
  EXPECT_EQ(Bits(sharded.norm_coeff), Bits(unsharded.norm_coeff));
  EXPECT_EQ(Bits(sharded.final_max_error), Bits(unsharded.final_max_error));
  EXPECT_EQ(sharded.final_quality.count, unsharded.final_quality.count);
  EXPECT_EQ(Bits(sharded.final_quality.min), Bits(unsharded.final_quality.min));
  EXPECT_EQ(sharded.tets_reoriented, unsharded.tets_reoriented);
  if (unsharded.stop_reason == StopReason::kTetBudget) {
    EXPECT_EQ(sharded.next_iteration_tets, unsharded.next_iteration_tets);
  }
  if (unsharded.stop_reason == StopReason::kQualityFloor) {
    EXPECT_EQ(Bits(sharded.next_iteration_min_quality), Bits(unsharded.next_iteration_min_quality));
  }
  // With every tet sampled, the lattice is the same set of points; only sums are reordered.
  if (unsharded.lattice.tets_sampled == unsharded.final_quality.count) {
    const LatticeStats& e = unsharded.lattice;
    const LatticeStats& a = sharded.lattice;
    EXPECT_EQ(a.tets_sampled, e.tets_sampled);
    EXPECT_EQ(a.points_sampled, e.points_sampled);
    EXPECT_EQ(Bits(a.max_error), Bits(e.max_error));
    EXPECT_NEAR(a.mean_error, e.mean_error, 1e-12 + 1e-9 * e.mean_error);
    EXPECT_NEAR(a.share_above_epsilon, e.share_above_epsilon, 1e-12);
    EXPECT_NEAR(a.volume_mean_error, e.volume_mean_error, 1e-12 + 1e-9 * e.volume_mean_error);
    EXPECT_NEAR(a.volume_share_above_epsilon, e.volume_share_above_epsilon, 1e-9);
  }
  ASSERT_EQ(sharded.iterations.size(), unsharded.iterations.size());
  for (size_t i = 0; i < unsharded.iterations.size(); ++i) {
    const IterationStats& e = unsharded.iterations[i];
    const IterationStats& a = sharded.iterations[i];
    SCOPED_TRACE(::testing::Message() << "iteration " << e.iteration);
    EXPECT_EQ(a.iteration, e.iteration);
    EXPECT_EQ(a.initial_tets, e.initial_tets);
    EXPECT_EQ(a.final_tets, e.final_tets);
    EXPECT_EQ(a.tets_with_error, e.tets_with_error);
    EXPECT_EQ(a.configurations, e.configurations);
    EXPECT_EQ(a.schonhardt_prisms, e.schonhardt_prisms);
    EXPECT_EQ(Bits(a.max_error), Bits(e.max_error));
    EXPECT_EQ(Bits(a.quality.min), Bits(e.quality.min));
    EXPECT_EQ(a.quality.count, e.quality.count);
    if (whole_mesh_statistics) {
      EXPECT_EQ(a.edges, e.edges);
      EXPECT_EQ(a.split_edges, e.split_edges);
      EXPECT_EQ(a.other_tilings, e.other_tilings);
      // The same edges and errors, summed in the merged mesh's order (numbered part by part).
      EXPECT_NEAR(a.mean_error, e.mean_error, 1e-13 * e.mean_error);
      if (i == 0) {
        EXPECT_EQ(Bits(a.mean_error), Bits(e.mean_error));
      }
    } else {
      // Edges on part boundaries are counted once per part.
      EXPECT_GE(a.edges, e.edges);
      EXPECT_GE(a.split_edges, e.split_edges);
    }
  }
  // Every scheme's merged mesh is measured whole (the paper path took the parts' mean until an
  // outside check found 0.020902 against 0.020730 on the same mesh, 2026-11-28).
  EXPECT_NEAR(sharded.final_mean_error, unsharded.final_mean_error,
              1e-13 * unsharded.final_mean_error);
}

}  // namespace tetrefine::testing
