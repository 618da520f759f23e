// Halo parts and the merge of one iteration's owned children, without servers: the halo is the
// rings it claims, every tet is owned once, and one part with the whole mesh merges back into
// exactly the core's iteration, statistics included.

#include "sharding/halo_parts.h"

#include <algorithm>
#include <set>
#include <vector>

#include "core/refine.h"
#include "gtest/gtest.h"
#include "tests/support/geometry.h"

namespace tetrefine::testing {
namespace {

// Tets sharing a vertex with one of `tets`, and those tets.
std::set<uint32_t> OneRingOut(const Mesh& mesh, const std::set<uint32_t>& tets) {
  std::set<uint32_t> vertices;
  for (uint32_t t : tets) vertices.insert(mesh.tets[t].begin(), mesh.tets[t].end());
  std::set<uint32_t> out = tets;
  for (uint32_t t = 0; t < mesh.tets.size(); ++t) {
    for (uint32_t v : mesh.tets[t]) {
      if (vertices.contains(v)) out.insert(t);
    }
  }
  return out;
}

TEST(HaloPartsTest, AHaloIsItsRingsAndEveryTetIsOwnedOnce) {
  const Mesh mesh = FiveTetMesh({0.0, 0.0, 0.0}, {12.0, 5.0, 4.0}, {12, 5, 4});
  const auto groups = sharding::PartitionTets(mesh, 3);
  for (int rings : {0, 1, 2, 5}) {
    SCOPED_TRACE(::testing::Message() << "rings = " << rings);
    const std::vector<sharding::HaloPart> parts = sharding::ExtractHaloParts(mesh, groups, rings);
    ASSERT_EQ(parts.size(), groups.size());
    std::vector<int> owners(mesh.tets.size(), 0);
    for (size_t p = 0; p < parts.size(); ++p) {
      const sharding::HaloPart& h = parts[p];
      ASSERT_EQ(h.owned.size(), h.part.mesh.tets.size());
      ASSERT_EQ(h.part.input_tet.size(), h.part.mesh.tets.size());
      std::set<uint32_t> expected(groups[p].begin(), groups[p].end());
      for (int r = 0; r < rings; ++r) expected = OneRingOut(mesh, expected);
      const std::set<uint32_t> got(h.part.input_tet.begin(), h.part.input_tet.end());
      EXPECT_EQ(got, expected);
      for (size_t t = 0; t < h.owned.size(); ++t) {
        const uint32_t whole = h.part.input_tet[t];
        const bool in_group = std::binary_search(groups[p].begin(), groups[p].end(), whole);
        EXPECT_EQ(h.owned[t] != 0, in_group);
        owners[whole] += h.owned[t];
        for (int c = 0; c < 4; ++c) {  // the part's tet is the whole tet
          EXPECT_EQ(h.part.mesh.points[h.part.mesh.tets[t][c]], mesh.points[mesh.tets[whole][c]]);
        }
      }
    }
    for (int n : owners) ASSERT_EQ(n, 1);
  }
}

// One part holding the whole mesh: the merge is the core's own iteration, and the statistics it
// derives from the merged mesh (NTwE, split edges, configurations, Steiner points) are the core's.
TEST(HaloPartsTest, MergingOneWholePartGivesTheCoresIterationAndStatistics) {
  const Volume volume = TestVolume({14, 12, 10});
  Mesh mesh = FiveTetMesh({0.5, 0.5, 0.5}, {12.5, 10.5, 8.5}, {6, 5, 4});
  for (size_t t = 0; t < mesh.tets.size(); ++t) mesh.labels.push_back(static_cast<int>(t % 4));
  for (const RefineScheme scheme : {RefineScheme::kPaper, RefineScheme::kLongestEdge}) {
    SCOPED_TRACE(std::string(RefineSchemeName(scheme)));
    RefineOptions options;
    options.scheme = scheme;
    options.epsilon = 0.004;
    options.max_iterations = 1;
    options.lattice_n = 0;
    options.track_parents = true;
    absl::StatusOr<RefineResult> refined = Refine(volume, mesh, options);
    ASSERT_TRUE(refined.ok()) << refined.status();
    ASSERT_EQ(refined->iterations.size(), 1u);
    const IterationStats& core = refined->iterations[0];
    ASSERT_GT(core.split_edges, 0);

    sharding::WholeMesh before;
    before.mesh = mesh;
    for (const Vec3& p : mesh.points) before.mesh.values.push_back(volume.Sample(p));
    before.tet_iteration.assign(mesh.tets.size(), 0);
    before.tet_quality.assign(mesh.tets.size(), 0.5f);
    for (uint32_t t = 0; t < mesh.tets.size(); ++t) before.tet_parent.push_back(t);
    const auto parts = sharding::ExtractHaloParts(mesh, sharding::PartitionTets(mesh, 1), 0);
    absl::StatusOr<sharding::MergedIteration> merged =
        sharding::MergeOwnedChildren(before, parts, {&*refined}, 7);
    ASSERT_TRUE(merged.ok()) << merged.status();
    const sharding::WholeMesh& whole = merged->whole;
    // New vertices are numbered in the order the merge meets them: compare positions.
    ASSERT_EQ(whole.mesh.points.size(), refined->mesh.points.size());
    ASSERT_EQ(whole.mesh.tets.size(), refined->mesh.tets.size());
    for (size_t t = 0; t < whole.mesh.tets.size(); ++t) {
      for (int c = 0; c < 4; ++c) {
        ASSERT_EQ(whole.mesh.points[whole.mesh.tets[t][c]],
                  refined->mesh.points[refined->mesh.tets[t][c]])
            << "tet " << t << " corner " << c;
      }
    }
    EXPECT_EQ(whole.mesh.labels, refined->mesh.labels);
    EXPECT_EQ(whole.tet_parent, refined->tet_parent);
    EXPECT_EQ(whole.tet_quality, refined->tet_quality);
    for (size_t t = 0; t < whole.tet_iteration.size(); ++t) {
      ASSERT_EQ(whole.tet_iteration[t], refined->tet_iteration[t] == 0 ? 0 : 7);
    }
    EXPECT_EQ(merged->split_tets, core.tets_with_error);
    EXPECT_EQ(merged->split_edges, core.split_edges);
    EXPECT_EQ(merged->configurations, core.configurations);
    EXPECT_EQ(merged->steiner_points, core.schonhardt_prisms);
    EXPECT_EQ(merged->worst_new_quality, [&] {
      float worst = 1.0f;
      for (size_t t = 0; t < whole.tet_quality.size(); ++t) {
        if (refined->tet_iteration[t] != 0) worst = std::min(worst, refined->tet_quality[t]);
      }
      return static_cast<double>(worst);
    }());
  }
}

TEST(HaloPartsTest, AResultWithoutParentsIsRefused) {
  const Volume volume = TestVolume({14, 12, 10});
  const Mesh mesh = FiveTetMesh({0.5, 0.5, 0.5}, {12.5, 10.5, 8.5}, {3, 3, 3});
  RefineOptions options;
  options.epsilon = 0.004;
  options.max_iterations = 1;
  options.lattice_n = 0;
  absl::StatusOr<RefineResult> refined = Refine(volume, mesh, options);
  ASSERT_TRUE(refined.ok());
  sharding::WholeMesh before;
  before.mesh = mesh;
  before.tet_iteration.assign(mesh.tets.size(), 0);
  before.tet_quality.assign(mesh.tets.size(), 0.5f);
  before.tet_parent.assign(mesh.tets.size(), 0);
  const auto parts = sharding::ExtractHaloParts(mesh, sharding::PartitionTets(mesh, 1), 0);
  absl::StatusOr<sharding::MergedIteration> merged =
      sharding::MergeOwnedChildren(before, parts, {&*refined}, 1);
  EXPECT_EQ(merged.status().code(), absl::StatusCode::kInternal);
}

}  // namespace
}  // namespace tetrefine::testing
