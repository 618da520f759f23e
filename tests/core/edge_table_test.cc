// The edge table and the counting sort under it: the unique edges of refined meshes (whose old
// vertices collect long buckets) against a std::set, and the same table for every thread count.
#include "core/edge_table.h"

#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cstdio>
#include <random>
#include <set>
#include <utility>

#include "core/counting_sort.h"
#include "core/refine.h"
#include "core/subdivide.h"
#include "core/tet_topology.h"
#include "tests/support/geometry.h"

namespace tetrefine {
namespace {

// A 5-tet box mesh refined by `iterations` rounds of Refine on a rough field: some edges split,
// some not, and the old vertices end with dozens of edges.
Mesh RefinedMesh(uint64_t seed, int iterations) {
  GridGeometry g;
  g.dims = {20, 20, 20};
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const double fx = 0.3 + u(rng), fy = 0.3 + u(rng), fz = 0.3 + u(rng);
  Volume v = testing::AnalyticVolume(g, [&](const Vec3& p) {
    return std::sin(fx * p[0]) * std::cos(fy * p[1]) + std::sin(fz * p[2]);
  });
  RefineOptions o;
  o.epsilon = 0.01;
  o.max_iterations = iterations;
  o.lattice_n = 0;
  auto r = Refine(v, testing::FiveTetMesh({0, 0, 0}, {19, 19, 19}, {4, 4, 4}), o);
  EXPECT_TRUE(r.ok()) << r.status();
  return r->mesh;
}

TEST(EdgeTableTest, ListsEachEdgeOnceInOrderOnRefinedMeshes) {
  for (uint64_t seed : testing::Seeds(4)) {
    std::printf("seed %llu\n", static_cast<unsigned long long>(seed));
    const Mesh m = RefinedMesh(seed, 3);
    const auto reference = testing::UniqueEdges(m.tets);
    const EdgeTable table = BuildEdgeTable(m.tets, static_cast<int64_t>(m.points.size()));
    ASSERT_EQ(table.size(), static_cast<int64_t>(reference.size()));
    auto it = reference.begin();
    for (uint32_t v = 0; v + 1 < table.first.size(); ++v) {
      for (uint32_t e = table.first[v]; e < table.first[v + 1]; ++e, ++it) {
        ASSERT_EQ(std::make_pair(v, table.second[e]), *it) << "edge " << e;
        ASSERT_EQ(table.FirstOf(e), v);
      }
    }
    // Before deduplication a bucket holds each edge once per tet around it; past 32 entries a
    // hash set drops the repeats, and these meshes must reach that path.
    std::vector<int> raw(m.points.size(), 0);
    for (const Tet& t : m.tets) {
      for (int i = 0; i < 4; ++i) {
        for (int j = i + 1; j < 4; ++j) ++raw[std::min(t[i], t[j])];
      }
    }
    EXPECT_GT(*std::max_element(raw.begin(), raw.end()), 32);
  }
}

// UpdateEdgeTable against BuildEdgeTable: the mesh after k iterations, and after k + 1, of every
// scheme; the split edges are the table's edges the mesh after no longer has.
TEST(EdgeTableTest, UpdateFromTheMeshBeforeIsTheBuiltTable) {
  GridGeometry g;
  g.dims = {20, 20, 20};
  int updates = 0;
  for (uint64_t seed : testing::Seeds(3)) {
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    const double fx = 0.3 + u(rng), fy = 0.3 + u(rng), fz = 0.3 + u(rng);
    const Volume v = testing::AnalyticVolume(g, [&](const Vec3& p) {
      return std::sin(fx * p[0]) * std::cos(fy * p[1]) + std::sin(fz * p[2]);
    });
    const Mesh input = testing::FiveTetMesh({0, 0, 0}, {19, 19, 19}, {4, 4, 4});
    for (const auto& [scheme, certify] :
         {std::pair{RefineScheme::kPaper, false}, std::pair{RefineScheme::kLongestEdge, false},
          std::pair{RefineScheme::kLongestEdge, true}}) {
      RefineOptions o;
      o.epsilon = 0.01;
      o.lattice_n = certify ? 4 : 0;  // certify samples a lattice in every tet
      o.scheme = scheme;
      o.certify = certify;
      o.max_iterations = 0;
      auto before = Refine(v, input, o);
      ASSERT_TRUE(before.ok()) << before.status();
      for (int k = 1; k <= 3; ++k) {
        o.max_iterations = k;
        auto after = Refine(v, input, o);
        ASSERT_TRUE(after.ok()) << after.status();
        if (after->iterations.size() < static_cast<size_t>(k)) break;
        const Mesh& m0 = before->mesh;
        const Mesh& m1 = after->mesh;
        const EdgeTable old_table = BuildEdgeTable(m0.tets, static_cast<int64_t>(m0.points.size()));
        const auto now = testing::UniqueEdges(m1.tets);
        FillLater<uint8_t> split(old_table.size());
        for (uint32_t a = 0; a + 1 < old_table.first.size(); ++a) {
          for (uint32_t e = old_table.first[a]; e < old_table.first[a + 1]; ++e) {
            split[e] = now.count({a, old_table.second[e]}) == 0;
          }
        }
        const EdgeTable built = BuildEdgeTable(m1.tets, static_cast<int64_t>(m1.points.size()));
        for (int threads : {1, 3}) {
          EdgeTable updated;
          tbb::task_arena(threads).execute([&] {
            updated = UpdateEdgeTable(old_table, split, m1.tets, after->tet_iteration, k,
                                      static_cast<int64_t>(m1.points.size()));
          });
          ASSERT_EQ(updated.first, built.first) << "seed " << seed << " iteration " << k;
          ASSERT_EQ(updated.second, built.second) << "seed " << seed << " iteration " << k;
          EXPECT_TRUE(updated.tet_edges.empty());
        }
        ++updates;
        before = std::move(after);
      }
    }
  }
  EXPECT_GE(updates, 20);
}

// UpdateTetEdges after a real subdivision (random marks on a refined mesh, from a few edges to a
// third of them) gives AddTetEdges' array; when the mesh grew by at most an eighth it rewrote
// the old array in place, for 1 and 3 threads (different chunks, different saved entries).
TEST(EdgeTableTest, UpdatedTetEdgesAreTheLookedUpOnes) {
  GridGeometry g;
  g.dims = {20, 20, 20};
  const Volume volume = testing::AnalyticVolume(
      g, [](const Vec3& p) { return std::sin(0.7 * p[0]) + std::cos(0.5 * p[1] * p[2]); });
  int in_place = 0;
  for (uint64_t seed : testing::Seeds(3)) {
    const Mesh m = RefinedMesh(seed, 2);
    for (const double fraction : {0.0005, 0.005, 0.02, 0.3}) {
      for (int threads : {1, 3}) {
        tbb::task_arena(threads).execute([&] {
          refine_internal::State state;
          state.points = &m.points;
          state.tets = &m.tets;
          for (const Vec3& p : m.points) state.mesh.values.push_back(volume.Sample(p));
          state.tet_iteration.assign(m.tets.size(), 0);
          state.tet_quality.assign(m.tets.size(), 1.0f);
          EdgeTable before = BuildEdgeTable(m.tets, static_cast<int64_t>(m.points.size()));
          AddTetEdges(m.tets, &before);
          refine_internal::EdgeErrors errors;
          std::mt19937_64 rng(seed);
          std::uniform_real_distribution<double> u(0.0, 1.0);
          errors.split.resize(before.size());
          errors.mid_value.assign(before.size(), 0.0);
          for (int64_t e = 0; e < before.size(); ++e) errors.split[e] = u(rng) < fraction;
          const std::function<bool()> never = [] { return false; };
          refine_internal::CancelFlag cancel(never);
          refine_internal::StepLimits limits;
          limits.max_tets = 1 << 30;
          IterationStats stats;
          int64_t next_tets = 0;
          double next_quality = 0.0;
          TetSuccession succession;
          ASSERT_EQ(refine_internal::Subdivide(volume, before, errors, 1, limits, cancel, state,
                                               stats, &next_tets, &next_quality, &succession),
                    refine_internal::StepOutcome::kApplied);
          const Mesh& after = state.mesh;
          FillLater<uint32_t> remap;
          EdgeTable updated = UpdateEdgeTable(before, errors.split, after.tets, state.tet_iteration,
                                              1, static_cast<int64_t>(after.points.size()), &remap);
          EdgeTable looked_up =
              BuildEdgeTable(after.tets, static_cast<int64_t>(after.points.size()));
          AddTetEdges(after.tets, &looked_up);
          const auto* old_array = before.tet_edges.data();
          updated.tet_edges = std::move(before.tet_edges);
          UpdateTetEdges(after.tets, succession, remap, &updated);
          ASSERT_EQ(updated.tet_edges.size(), after.tets.size());
          EXPECT_TRUE(std::equal(updated.tet_edges.begin(), updated.tet_edges.end(),
                                 looked_up.tet_edges.begin()))
              << "seed " << seed << ", split fraction " << fraction << ", " << threads
              << " threads";
          if (after.tets.size() <= m.tets.size() + m.tets.size() / 8) {
            EXPECT_EQ(updated.tet_edges.data(), old_array) << "not rewritten in place";
            ++in_place;
          }
        });
      }
    }
  }
  EXPECT_GE(in_place, 6);
}

TEST(EdgeTableTest, TetEdgesNameTheTetsOwnEdges) {
  const Mesh m = RefinedMesh(testing::Seeds(1)[0], 2);
  EdgeTable table = BuildEdgeTable(m.tets, static_cast<int64_t>(m.points.size()));
  AddTetEdges(m.tets, &table);
  for (size_t t = 0; t < m.tets.size(); ++t) {
    for (int k = 0; k < 6; ++k) {
      const uint32_t e = table.tet_edges[t][k];
      const auto ends = std::minmax(m.tets[t][kTetEdges[k][0]], m.tets[t][kTetEdges[k][1]]);
      ASSERT_EQ(table.FirstOf(e), ends.first) << "tet " << t << " edge " << k;
      ASSERT_EQ(table.second[e], ends.second) << "tet " << t << " edge " << k;
    }
  }
}

// AddTetEdges refills the array a table already holds (a refinement passes the iteration
// before's): stale contents, larger or smaller, leave no trace.
TEST(EdgeTableTest, TetEdgesReuseAStaleArray) {
  const Mesh m = RefinedMesh(testing::Seeds(1)[0], 2);
  EdgeTable fresh = BuildEdgeTable(m.tets, static_cast<int64_t>(m.points.size()));
  AddTetEdges(m.tets, &fresh);
  for (const size_t stale_size : {m.tets.size() / 3, m.tets.size(), 2 * m.tets.size()}) {
    EdgeTable reused = BuildEdgeTable(m.tets, static_cast<int64_t>(m.points.size()));
    reused.tet_edges.assign(stale_size, {7, 7, 7, 7, 7, 7});
    AddTetEdges(m.tets, &reused);
    ASSERT_EQ(reused.tet_edges.size(), m.tets.size());
    EXPECT_TRUE(
        std::equal(reused.tet_edges.begin(), reused.tet_edges.end(), fresh.tet_edges.begin()))
        << "stale array of " << stale_size;
  }
}

TEST(EdgeTableTest, SameTableForEveryThreadCount) {
  const Mesh m = RefinedMesh(testing::Seeds(1)[0], 3);
  EdgeTable one;
  tbb::task_arena(1).execute(
      [&] { one = BuildEdgeTable(m.tets, static_cast<int64_t>(m.points.size())); });
  for (int threads : {2, 3, 4}) {
    EdgeTable many;
    tbb::task_arena(threads).execute(
        [&] { many = BuildEdgeTable(m.tets, static_cast<int64_t>(m.points.size())); });
    EXPECT_EQ(many.first, one.first) << threads << " threads";
    EXPECT_EQ(many.second, one.second) << threads << " threads";
  }
}

// Every bucket lists its entries in item order, whatever the number of chunks.
TEST(CountingSortTest, BucketsKeepItemOrderForEveryThreadCount) {
  for (uint64_t seed : testing::Seeds(3)) {
    std::printf("seed %llu\n", static_cast<unsigned long long>(seed));
    std::mt19937_64 rng(seed);
    const int64_t items = 50'000 + static_cast<int64_t>(rng() % 20'000);
    const int64_t buckets = 1 + static_cast<int64_t>(rng() % 3'000);
    std::vector<std::array<int64_t, 2>> emits(items);  // each item: two buckets
    for (auto& e : emits)
      e = {static_cast<int64_t>(rng() % buckets), static_cast<int64_t>(rng() % buckets)};
    // Reference: entry (item, k) appended to its bucket in item order.
    std::vector<std::vector<int64_t>> expected(buckets);
    for (int64_t i = 0; i < items; ++i) {
      for (int k = 0; k < 2; ++k) expected[emits[i][k]].push_back(2 * i + k);
    }
    for (int threads : {1, 2, 4, 7}) {
      std::vector<int64_t> out;
      BucketLayout layout;
      tbb::task_arena(threads).execute([&] {
        layout = CountingSort(
            items, buckets,
            [&](int64_t i, auto add) {
              add(emits[i][0], 1);
              add(emits[i][1], 1);
            },
            [&](uint64_t total) { out.assign(total, -1); },
            [&](int64_t i, auto slot) {
              out[slot(emits[i][0], 1)] = 2 * i;
              out[slot(emits[i][1], 1)] = 2 * i + 1;
            });
      });
      ASSERT_EQ(layout.size(), static_cast<uint64_t>(2 * items));
      for (int64_t b = 0; b < buckets; ++b) {
        const std::vector<int64_t> got(out.begin() + layout.start[b],
                                       out.begin() + layout.start[b + 1]);
        ASSERT_EQ(got, expected[b]) << "bucket " << b << ", " << threads << " threads";
      }
    }
  }
}

}  // namespace
}  // namespace tetrefine
