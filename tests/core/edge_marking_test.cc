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

}  // namespace
}  // namespace tetrefine::refine_internal
