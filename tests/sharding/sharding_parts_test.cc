// The pieces of sharded refinement, without servers: partition, slabs, stop rule, edge count.

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <set>

#include "gtest/gtest.h"
#include "sharding/mesh_partition.h"
#include "sharding/result_combine.h"
#include "sharding/volume_slab.h"
#include "tests/support/geometry.h"

namespace tetrefine::testing {
namespace {

// TETREFINE_SEED pins one seed; otherwise a fixed few. Each is printed.
std::vector<uint64_t> SlabSeeds() {
  if (const char* pinned = std::getenv("TETREFINE_SEED"))
    return {std::strtoull(pinned, nullptr, 10)};
  return {1, 2, 3, 4, 5};
}

std::vector<std::vector<uint32_t>> PartitionTetsTwice(const Mesh& mesh, int parts) {
  auto first = sharding::PartitionTets(mesh, parts);
  EXPECT_EQ(first, sharding::PartitionTets(mesh, parts)) << "not deterministic";
  return first;
}

TEST(PartitionTest, EveryTetInExactlyOnePartAndDeterministic) {
  const Mesh mesh = FiveTetMesh({0.0, 0.0, 0.0}, {9.0, 7.0, 5.0}, {9, 7, 5});
  for (int k : {1, 2, 3, 4, 5, 7, 16}) {
    SCOPED_TRACE(::testing::Message() << "parts = " << k);
    const auto groups = PartitionTetsTwice(mesh, k);
    ASSERT_EQ(groups.size(), static_cast<size_t>(k));
    std::vector<int> seen(mesh.tets.size(), 0);
    size_t smallest = mesh.tets.size(), largest = 0;
    for (const auto& g : groups) {
      EXPECT_TRUE(std::is_sorted(g.begin(), g.end()));
      smallest = std::min(smallest, g.size());
      largest = std::max(largest, g.size());
      for (uint32_t t : g) ++seen[t];
    }
    EXPECT_TRUE(std::all_of(seen.begin(), seen.end(), [](int n) { return n == 1; }));
    EXPECT_LE(largest - smallest, 1u) << "bisection in proportion keeps parts balanced";
  }
}

TEST(PartitionTest, MorePartsThanTetsIsClamped) {
  const Mesh mesh = FiveTetMesh({0.0, 0.0, 0.0}, {1.0, 1.0, 1.0}, {1, 1, 1});
  EXPECT_EQ(sharding::PartitionTets(mesh, 100).size(), 5u);
  EXPECT_EQ(sharding::PartitionTets(mesh, 0).size(), 1u);
}

TEST(PartitionTest, PartsAreMeshesOfTheirOwn) {
  const Mesh mesh = FiveTetMesh({0.0, 0.0, 0.0}, {6.0, 6.0, 6.0}, {6, 6, 6});
  const auto groups = sharding::PartitionTets(mesh, 3);
  const auto parts = sharding::ExtractParts(mesh, groups);
  ASSERT_EQ(parts.size(), 3u);
  for (size_t p = 0; p < parts.size(); ++p) {
    const sharding::MeshPart& part = parts[p];
    EXPECT_TRUE(std::is_sorted(part.input_vertex.begin(), part.input_vertex.end()));
    ASSERT_EQ(part.mesh.tets.size(), groups[p].size());
    for (size_t t = 0; t < groups[p].size(); ++t) {
      for (int c = 0; c < 4; ++c) {
        EXPECT_EQ(part.input_vertex[part.mesh.tets[t][c]], mesh.tets[groups[p][t]][c]);
      }
    }
    for (const Vec3& q : part.mesh.points) {
      EXPECT_TRUE(sharding::InBox(q, part.box_lo, part.box_hi));
    }
  }
}

// Sampling a slab cut for some points gives the same bits as the whole volume, at every point of
// the points' bounding box.
TEST(SlabTest, SlabSamplesLikeTheWholeVolume) {
  const Volume whole = TestVolume({20, 18, 16}, VoxelType::kUint16);
  for (uint64_t seed : SlabSeeds()) {
    std::printf("seed %llu\n", static_cast<unsigned long long>(seed));
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> x(0.0, 19.0), y(0.0, 17.0), z(0.0, 15.0);
    std::vector<Vec3> points = {{x(rng), y(rng), z(rng)}, {x(rng), y(rng), z(rng)}};
    // Grid-aligned corners too: a point on a cell face may take either neighbouring cell.
    points.push_back({std::floor(points[0][0]), std::floor(points[0][1]), 15.0});
    const sharding::SlabBox box = sharding::SlabCovering(whole, points, false);
    absl::StatusOr<Volume> slab = sharding::CutSlab(whole, box);
    ASSERT_TRUE(slab.ok()) << slab.status();
    Vec3 lo = points[0], hi = points[0];
    for (const Vec3& p : points) {
      for (int a = 0; a < 3; ++a) {
        lo[a] = std::min(lo[a], p[a]);
        hi[a] = std::max(hi[a], p[a]);
      }
    }
    std::uniform_real_distribution<double> t(0.0, 1.0);
    for (int i = 0; i < 500; ++i) {
      Vec3 q;
      for (int a = 0; a < 3; ++a) q[a] = lo[a] + (hi[a] - lo[a]) * t(rng);
      ASSERT_TRUE(slab->Contains(slab->ContinuousIndex(q)));
      EXPECT_EQ(std::bit_cast<uint64_t>(slab->Sample(q)), std::bit_cast<uint64_t>(whole.Sample(q)));
    }
    EXPECT_LT(slab->data().size(), whole.data().size() + 1);
  }
}

TEST(SlabTest, CutOutsideTheVolumeIsAnError) {
  const Volume whole = TestVolume({8, 8, 8});
  EXPECT_FALSE(sharding::CutSlab(whole, {{0, 0, 0}, {9, 8, 8}}).ok());
  EXPECT_FALSE(sharding::CutSlab(whole, {{3, 0, 0}, {4, 8, 8}}).ok());
}

TEST(CountEdgesTest, OneCubeOfFiveTets) {
  // 12 cube edges and 6 face diagonals; the centre tet adds none.
  EXPECT_EQ(sharding::CountEdges(FiveTetMesh({0.0, 0.0, 0.0}, {1.0, 1.0, 1.0}, {1, 1, 1})), 18);
}

// A part result with `final_tets` after each completed iteration and the given stop.
RefineResult Part(int64_t initial, std::vector<int64_t> final_tets, StopReason reason,
                  int64_t next_tets = 0, double next_quality = 0.0) {
  RefineResult r;
  r.initial_quality.count = initial;
  int64_t before = initial;
  for (size_t i = 0; i < final_tets.size(); ++i) {
    IterationStats s;
    s.iteration = static_cast<int>(i + 1);
    s.initial_tets = before;
    s.final_tets = final_tets[i];
    before = final_tets[i];
    r.iterations.push_back(s);
  }
  r.final_quality.count = before;
  r.stop_reason = reason;
  r.next_iteration_tets = next_tets;
  r.next_iteration_min_quality = next_quality;
  return r;
}

sharding::WholeStop Stop(const std::vector<RefineResult>& parts, int max_iterations,
                         int64_t max_tets) {
  std::vector<const RefineResult*> p;
  for (const RefineResult& r : parts) p.push_back(&r);
  return sharding::CombineStops(p, max_iterations, max_tets);
}

TEST(CombineStopsTest, ConvergedWhenEveryPartIs) {
  const auto s =
      Stop({Part(10, {20, 30}, StopReason::kConverged), Part(10, {15}, StopReason::kConverged)}, 8,
           1000);
  EXPECT_EQ(s.reason, StopReason::kConverged);
  EXPECT_EQ(s.iterations, 2);
}

TEST(CombineStopsTest, MaxIterationsWhenAnyPartHasEdgesLeft) {
  const auto s =
      Stop({Part(10, {20, 30}, StopReason::kMaxIterations), Part(10, {15}, StopReason::kConverged)},
           2, 1000);
  EXPECT_EQ(s.reason, StopReason::kMaxIterations);
  EXPECT_EQ(s.iterations, 2);
}

TEST(CombineStopsTest, BudgetCountsConvergedPartsToo) {
  // After iteration 3: 60 + 40 (converged after 1) = 100 > 99.
  const auto s =
      Stop({Part(10, {20, 40, 60}, StopReason::kConverged), Part(10, {40}, StopReason::kConverged)},
           8, 99);
  EXPECT_EQ(s.reason, StopReason::kTetBudget);
  EXPECT_EQ(s.iterations, 2);
  EXPECT_EQ(s.next_iteration_tets, 100);
}

TEST(CombineStopsTest, PartBudgetRefusalStopsTheWhole) {
  const auto s = Stop(
      {Part(10, {20}, StopReason::kTetBudget, 120), Part(10, {30, 50, 70}, StopReason::kConverged)},
      8, 100);
  EXPECT_EQ(s.reason, StopReason::kTetBudget);
  EXPECT_EQ(s.iterations, 1);
  EXPECT_EQ(s.next_iteration_tets, 170);
}

TEST(CombineStopsTest, EarliestQualityFloorWinsWithItsWorstTet) {
  const auto s = Stop({Part(10, {20, 30}, StopReason::kQualityFloor, 0, 0.01),
                       Part(10, {20}, StopReason::kQualityFloor, 0, 0.02),
                       Part(10, {20}, StopReason::kQualityFloor, 0, 0.005),
                       Part(10, {20, 30, 40}, StopReason::kMaxIterations)},
                      3, 1000);
  EXPECT_EQ(s.reason, StopReason::kQualityFloor);
  EXPECT_EQ(s.iterations, 1);
  EXPECT_EQ(s.next_iteration_min_quality, 0.005);
}

TEST(CombineStopsTest, BudgetBeforeQualityFloorInTheSameIteration) {
  const auto s = Stop({Part(10, {20}, StopReason::kQualityFloor, 0, 0.01),
                       Part(10, {20, 200}, StopReason::kConverged)},
                      8, 100);
  EXPECT_EQ(s.reason, StopReason::kTetBudget);
  EXPECT_EQ(s.iterations, 1);
}

TEST(CombineStopsTest, ZeroIterations) {
  EXPECT_EQ(Stop({Part(10, {}, StopReason::kMaxIterations)}, 0, 100).reason,
            StopReason::kMaxIterations);
  EXPECT_EQ(Stop({Part(10, {}, StopReason::kConverged)}, 0, 100).reason, StopReason::kConverged);
}

}  // namespace
}  // namespace tetrefine::testing
