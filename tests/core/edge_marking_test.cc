// The marking passes of the longest-edge scheme: they poll cancellation, so a cancelled call
// does not first run every closure and guard pass over a large mesh (the hardening fault test
// saw a server keep working 3.4 s past a client's deadline inside them).

#include "core/edge_marking.h"

#include <cstdint>
#include <functional>
#include <vector>

#include "core/edge_table.h"
#include "gtest/gtest.h"
#include "tests/support/geometry.h"

namespace tetrefine::refine_internal {
namespace {

struct Marked {
  Mesh mesh = testing::FiveTetMesh({0.0, 0.0, 0.0}, {6.0, 5.0, 4.0}, {6, 5, 4});
  EdgeTable edges;
  FillLater<uint8_t> split;

  Marked() {
    edges = BuildEdgeTable(mesh.tets, static_cast<int64_t>(mesh.points.size()));
    AddTetEdges(mesh.tets, &edges);
    split.assign(static_cast<size_t>(edges.size()), 0);
    split[edges.tet_edges[0][0]] = 1;  // one split edge: the closure and the guard have work
  }
};

TEST(EdgeMarkingTest, ClosureAndGuardMarkNothingOnceCancelled) {
  const std::function<bool()> never = [] { return false; };
  const std::function<bool()> always = [] { return true; };
  {
    Marked m;
    CancelFlag running(never);
    EXPECT_GT(CloseToLongestEdges(m.mesh.points, m.mesh.tets, m.edges, 4, m.split, running), 0)
        << "the case gives the closure nothing to do";
    EXPECT_GT(PromoteBadSplits(m.mesh.points, m.mesh.tets, m.edges, 0.99, m.split, running), 0)
        << "the case gives the guard nothing to do";
  }
  Marked m;
  const FillLater<uint8_t> before = m.split;
  CancelFlag cancelled(always);
  EXPECT_EQ(CloseToLongestEdges(m.mesh.points, m.mesh.tets, m.edges, 4, m.split, cancelled), 0);
  EXPECT_EQ(PromoteBadSplits(m.mesh.points, m.mesh.tets, m.edges, 0.99, m.split, cancelled), 0);
  EXPECT_TRUE(cancelled.IsSet());
  EXPECT_TRUE(m.split == before);
}

// The closure with the longest-edge cache shared across calls marks exactly what it marks with
// a fresh cache per call, and the cache holds LongestEdge for every tet it filled: the cache is
// a saving, never a different answer. Random jittered meshes, several split seeds, the guard
// between the closure calls as in an iteration of the longest-edge scheme.
TEST(EdgeMarkingTest, SharedLongestEdgeCacheChangesNoMark) {
  const std::function<bool()> never = [] { return false; };
  for (uint32_t seed = 1; seed <= 12; ++seed) {
    Mesh mesh = testing::FiveTetMesh({0.0, 0.0, 0.0}, {6.0, 5.0, 4.0}, {6, 5, 4});
    uint32_t state = seed * 2654435761u;
    auto next = [&state] {
      state = state * 1664525u + 1013904223u;
      return static_cast<double>(state >> 8) / static_cast<double>(1u << 24);
    };
    for (Vec3& p : mesh.points) {
      for (double& x : p) x += 0.2 * (next() - 0.5);  // interior jitter keeps tets positive
    }
    EdgeTable edges = BuildEdgeTable(mesh.tets, static_cast<int64_t>(mesh.points.size()));
    AddTetEdges(mesh.tets, &edges);
    FillLater<uint8_t> fresh(static_cast<size_t>(edges.size()), 0);
    for (int64_t e = 0; e < edges.size(); ++e) fresh[e] = next() < 0.03 ? 1 : 0;
    FillLater<uint8_t> cached = fresh;
    FillLater<uint8_t> cache(mesh.tets.size(), kLongestUnknown);
    CancelFlag running(never);
    for (int call = 0; call < 3; ++call) {
      if (call > 0) {
        PromoteBadSplits(mesh.points, mesh.tets, edges, 0.65, fresh, running);
        PromoteBadSplits(mesh.points, mesh.tets, edges, 0.65, cached, running);
      }
      const int64_t a = CloseToLongestEdges(mesh.points, mesh.tets, edges, 4, fresh, running);
      const int64_t b =
          CloseToLongestEdges(mesh.points, mesh.tets, edges, 4, cached, running, &cache);
      EXPECT_EQ(a, b) << "seed " << seed << ", call " << call;
      EXPECT_TRUE(fresh == cached) << "seed " << seed << ", call " << call;
    }
    int64_t filled = 0;
    for (size_t t = 0; t < mesh.tets.size(); ++t) {
      if (cache[t] == kLongestUnknown) continue;
      ++filled;
      const Tet& tet = mesh.tets[t];
      EXPECT_EQ(cache[t], LongestEdge({mesh.points[tet[0]], mesh.points[tet[1]],
                                       mesh.points[tet[2]], mesh.points[tet[3]]}))
          << "seed " << seed << ", tet " << t;
    }
    EXPECT_GT(filled, 0) << "seed " << seed << ": the closure had no tet to look at";
  }
}

}  // namespace
}  // namespace tetrefine::refine_internal
