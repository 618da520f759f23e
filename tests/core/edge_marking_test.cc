// The marking passes of the longest-edge scheme: they poll cancellation, so a cancelled call
// does not first run every closure and guard pass over a large mesh (the hardening fault test
// saw a server keep working 3.4 s past a client's deadline inside them).

#include "core/edge_marking.h"

#include <algorithm>
#include <array>
#include <cstdint>
#include <functional>
#include <map>
#include <vector>

#include "core/edge_table.h"
#include "core/quality.h"
#include "core/tet_topology.h"
#include "core/tets_around.h"
#include "core/vec3_ops.h"
#include "gtest/gtest.h"
#include "tests/support/geometry.h"

namespace tetrefine::refine_internal {
namespace {

// A 6x5x4-cell box. Built out of line: inlined into Marked's constructor, GCC 12's unity build
// of this file reported a dangling pointer to the argument temporaries (-Wdangling-pointer, a
// false positive: FiveTetMesh copies them).
Mesh SmallBox() { return testing::FiveTetMesh({0.0, 0.0, 0.0}, {6.0, 5.0, 4.0}, {6, 5, 4}); }

// Uniform numbers in [0, 1) from a linear congruential generator: the same on every platform.
struct Lcg {
  uint32_t state;
  double operator()() {
    state = state * 1664525u + 1013904223u;
    return static_cast<double>(state >> 8) / static_cast<double>(1u << 24);
  }
};

// A box [0, hi] of 5-tet cells whose points are each moved by up to 0.1 per axis (interior
// jitter keeps tets positive), with its edge table and tet edges. `next` is left where the jitter
// stopped, for the test's random marks.
struct Jittered {
  Mesh mesh;
  EdgeTable edges;
};
Jittered JitteredBox(const Vec3& hi, const std::array<int, 3>& cells, Lcg& next) {
  Jittered j{testing::FiveTetMesh({0.0, 0.0, 0.0}, hi, cells), {}};
  for (Vec3& p : j.mesh.points) {
    for (double& x : p) x += 0.2 * (next() - 0.5);
  }
  j.edges = BuildEdgeTable(j.mesh.tets, static_cast<int64_t>(j.mesh.points.size()));
  AddTetEdges(j.mesh.tets, &j.edges);
  return j;
}

struct Marked {
  Mesh mesh = SmallBox();
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
    EXPECT_GT(
        PromoteBadSplits(m.mesh.points, m.mesh.tets, m.edges, 0.99, 0.0, false, m.split, running),
        0)
        << "the case gives the guard nothing to do";
  }
  Marked m;
  const FillLater<uint8_t> before = m.split;
  CancelFlag cancelled(always);
  EXPECT_EQ(CloseToLongestEdges(m.mesh.points, m.mesh.tets, m.edges, 4, m.split, cancelled), 0);
  EXPECT_EQ(
      PromoteBadSplits(m.mesh.points, m.mesh.tets, m.edges, 0.99, 0.0, false, m.split, cancelled),
      0);
  // The guard's last look, on a jittered box with many marks (on the plain box with one mark
  // the neighbours refuse every remedy).
  Lcg next{7};
  const Jittered box = JitteredBox({6.0, 5.0, 4.0}, {6, 5, 4}, next);
  FillLater<uint8_t> split(static_cast<size_t>(box.edges.size()), 0);
  for (int64_t e = 0; e < box.edges.size(); ++e) split[e] = next() < 0.15 ? 1 : 0;
  const TetsAround around(box.mesh.tets, static_cast<int64_t>(box.mesh.points.size()));
  {
    FillLater<uint8_t> marks = split;
    CancelFlag running(never);
    EXPECT_GT(FinalGuardPass(box.mesh.points, box.mesh.tets, box.edges, around, 0.6, 0.3, marks,
                             running, nullptr, nullptr),
              0)
        << "the case gives the guard's last look nothing to do";
  }
  FillLater<uint8_t> marks = split;
  EXPECT_EQ(FinalGuardPass(box.mesh.points, box.mesh.tets, box.edges, around, 0.6, 0.3, marks,
                           cancelled, nullptr, nullptr),
            0);
  EXPECT_TRUE(marks == split);
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
    Lcg next{seed * 2654435761u};
    const auto [mesh, edges] = JitteredBox({6.0, 5.0, 4.0}, {6, 5, 4}, next);
    FillLater<uint8_t> fresh(static_cast<size_t>(edges.size()), 0);
    for (int64_t e = 0; e < edges.size(); ++e) fresh[e] = next() < 0.03 ? 1 : 0;
    FillLater<uint8_t> cached = fresh;
    FillLater<uint16_t> cache(mesh.tets.size(), kTargetsUnknown);
    CancelFlag running(never);
    for (int call = 0; call < 3; ++call) {
      if (call > 0) {
        PromoteBadSplits(mesh.points, mesh.tets, edges, 0.65, 0.0, false, fresh, running);
        PromoteBadSplits(mesh.points, mesh.tets, edges, 0.65, 0.0, false, cached, running);
      }
      const int64_t a = CloseToLongestEdges(mesh.points, mesh.tets, edges, 4, fresh, running);
      const int64_t b =
          CloseToLongestEdges(mesh.points, mesh.tets, edges, 4, cached, running, &cache);
      EXPECT_EQ(a, b) << "seed " << seed << ", call " << call;
      EXPECT_TRUE(fresh == cached) << "seed " << seed << ", call " << call;
    }
    int64_t filled = 0;
    for (size_t t = 0; t < mesh.tets.size(); ++t) {
      if (cache[t] == kTargetsUnknown) continue;
      ++filled;
      const Tet& tet = mesh.tets[t];
      const std::array<Vec3, 4> p = {mesh.points[tet[0]], mesh.points[tet[1]], mesh.points[tet[2]],
                                     mesh.points[tet[3]]};
      EXPECT_EQ(cache[t], ClosureTargets(p)) << "seed " << seed << ", tet " << t;
    }
    EXPECT_GT(filled, 0) << "seed " << seed << ": the closure had no tet to look at";
  }
}

// The longest of the tet's local edges whose EdgeBit is in `among`, found plainly: by length,
// equal lengths by the smaller (lexicographically ordered) endpoint pair.
int PlainLongest(const std::array<Vec3, 4>& p, uint32_t among) {
  int best = -1;
  double best_length = -1.0;
  std::array<Vec3, 2> best_pair{};
  for (int k = 0; k < 6; ++k) {
    if ((among & EdgeBit(k)) == 0) continue;
    const Vec3& a = p[kTetEdges[k][0]];
    const Vec3& b = p[kTetEdges[k][1]];
    const double length = SquaredDistance(a, b);
    const std::array<Vec3, 2> pair = {std::min(a, b), std::max(a, b)};
    if (best < 0 || length > best_length || (length == best_length && pair < best_pair)) {
      best = k;
      best_length = length;
      best_pair = pair;
    }
  }
  return best;
}

// The local edges of face f (opposite corner f) as EdgeBit masks.
uint32_t FaceEdges(int f) {
  uint32_t bits = 0;
  for (int k = 0; k < 6; ++k) {
    if (kTetEdges[k][0] != f && kTetEdges[k][1] != f) bits |= EdgeBit(k);
  }
  return bits;
}

// ClosureTargets names the edges plain comparison names: the tet's longest edge is LongestEdge,
// each face's longest edge is the longest of its three, and the two tets of a face name the same
// edge. A regular box (many equal lengths: the tie-break decides) and jittered ones.
TEST(EdgeMarkingTest, ClosureTargetsAgreeWithPlainComparisonAndAcrossFaces) {
  for (uint32_t seed = 0; seed <= 6; ++seed) {
    Lcg next{seed * 2654435761u + 7u};
    Jittered box = JitteredBox({5.0, 4.0, 3.0}, {5, 4, 3}, next);
    if (seed == 0) box.mesh = testing::FiveTetMesh({0.0, 0.0, 0.0}, {5.0, 4.0, 3.0}, {5, 4, 3});
    const Mesh& mesh = box.mesh;
    // Each face (its sorted global corners) to the global edge its first tet called longest.
    std::map<std::array<uint32_t, 3>, std::array<uint32_t, 2>> face_longest;
    int shared_faces = 0;
    for (size_t t = 0; t < mesh.tets.size(); ++t) {
      const Tet& tet = mesh.tets[t];
      const std::array<Vec3, 4> p = {mesh.points[tet[0]], mesh.points[tet[1]], mesh.points[tet[2]],
                                     mesh.points[tet[3]]};
      const uint32_t targets = ClosureTargets(p);
      EXPECT_EQ(static_cast<int>(targets & 7u), LongestEdge(p)) << "seed " << seed << ", tet " << t;
      EXPECT_EQ(static_cast<int>(targets & 7u), PlainLongest(p, 63)) << "seed " << seed;
      for (int f = 0; f < 4; ++f) {
        const int k = static_cast<int>((targets >> (3 + 3 * f)) & 7u);
        EXPECT_EQ(k, PlainLongest(p, FaceEdges(f))) << "seed " << seed << ", tet " << t;
        std::array<uint32_t, 3> face;
        for (int i = 0, c = 0; c < 4; ++c) {
          if (c != f) face[i++] = tet[c];
        }
        std::sort(face.begin(), face.end());
        std::array<uint32_t, 2> edge = {tet[kTetEdges[k][0]], tet[kTetEdges[k][1]]};
        std::sort(edge.begin(), edge.end());
        const auto [it, inserted] = face_longest.emplace(face, edge);
        if (!inserted) {
          ++shared_faces;
          EXPECT_EQ(it->second, edge) << "seed " << seed << ": the tets of a face disagree";
        }
      }
    }
    EXPECT_GT(shared_faces, 100) << "seed " << seed;
  }
}

// A tet whose split edge is the longest edge of both its faces through it, but not the tet's own
// longest edge: the closure adds nothing (Plaza's rule; before 2026-11-28 it added the tet's
// longest edge, here 2-3, which is what docs/schemes.md "The closure without the tet rule"
// measured against).
TEST(EdgeMarkingTest, ClosureAddsNotTheTetsLongestEdgeWhenNoFaceAsksForIt) {
  Mesh mesh;
  // |01| = 2; |02| = |12| = 1.56 and |03| = |13| = 1.60 (01 is the longest of faces 012 and
  // 013); |23| = 2.11, the tet's longest edge.
  mesh.points = {{0.0, 0.0, 0.0}, {2.0, 0.0, 0.0}, {1.0, 1.2, 0.0}, {1.0, -0.6, 1.1}};
  mesh.tets = {{0, 1, 2, 3}};
  ASSERT_EQ(LongestEdge({mesh.points[0], mesh.points[1], mesh.points[2], mesh.points[3]}),
            EdgeIndex(2, 3));
  EdgeTable edges = BuildEdgeTable(mesh.tets, static_cast<int64_t>(mesh.points.size()));
  AddTetEdges(mesh.tets, &edges);
  FillLater<uint8_t> split(static_cast<size_t>(edges.size()), 0);
  split[edges.tet_edges[0][EdgeIndex(0, 1)]] = 1;
  const std::function<bool()> never = [] { return false; };
  CancelFlag running(never);
  EXPECT_EQ(CloseToLongestEdges(mesh.points, mesh.tets, edges, 8, split, running), 0);
  for (int k = 0; k < 6; ++k) {
    EXPECT_EQ(split[edges.tet_edges[0][k]] != 0, k == EdgeIndex(0, 1)) << "edge " << k;
  }
  // A split edge that is not the longest of a face through it brings that face's longest edge.
  split.assign(static_cast<size_t>(edges.size()), 0);
  split[edges.tet_edges[0][EdgeIndex(0, 2)]] = 1;
  EXPECT_GT(CloseToLongestEdges(mesh.points, mesh.tets, edges, 8, split, running), 0);
  EXPECT_NE(split[edges.tet_edges[0][EdgeIndex(0, 1)]], 0);  // face 012's longest
}

// The closure marks what its rule read plainly marks: each round, every face with a split edge
// (as the round before left them) splits its longest edge, and nothing else (not the tet's own
// longest edge, since 2026-11-28). Random jittered meshes, random marks, 1 to 6 rounds; the
// reference visits every tet in every round.
TEST(EdgeMarkingTest, ClosureMarksWhatEveryTetRoundByRoundMarks) {
  const std::function<bool()> never = [] { return false; };
  int multi_round_cases = 0;
  for (uint32_t seed = 1; seed <= 16; ++seed) {
    Lcg next{seed * 2246822519u};
    const auto [mesh, edges] = JitteredBox({8.0, 7.0, 6.0}, {8, 7, 6}, next);
    FillLater<uint8_t> marks(static_cast<size_t>(edges.size()), 0);
    for (int64_t e = 0; e < edges.size(); ++e) marks[e] = next() < 0.01 ? 1 : 0;
    for (int rounds = 1; rounds <= 6; ++rounds) {
      FillLater<uint8_t> expected = marks;
      int64_t expected_added = 0;
      for (int r = 0; r < rounds; ++r) {
        FillLater<uint8_t> after = expected;
        for (size_t t = 0; t < mesh.tets.size(); ++t) {
          const auto& te = edges.tet_edges[t];
          bool any = false;
          for (int k = 0; k < 6; ++k) any |= expected[te[k]] != 0;
          if (!any) continue;
          const Tet& tet = mesh.tets[t];
          const std::array<Vec3, 4> p = {mesh.points[tet[0]], mesh.points[tet[1]],
                                         mesh.points[tet[2]], mesh.points[tet[3]]};
          for (int f = 0; f < 4; ++f) {
            bool face_any = false;
            for (int k = 0; k < 6; ++k) {
              face_any |= (FaceEdges(f) & EdgeBit(k)) != 0 && expected[te[k]] != 0;
            }
            if (face_any) after[te[PlainLongest(p, FaceEdges(f))]] = 1;
          }
        }
        int64_t added = 0;
        for (int64_t e = 0; e < edges.size(); ++e) added += after[e] != expected[e];
        expected = after;
        expected_added += added;
        if (added == 0) break;
        if (r >= 1) ++multi_round_cases;
      }
      FillLater<uint8_t> got = marks;
      CancelFlag running(never);
      EXPECT_EQ(CloseToLongestEdges(mesh.points, mesh.tets, edges, rounds, got, running),
                expected_added)
          << "seed " << seed << ", " << rounds << " rounds";
      EXPECT_TRUE(got == expected) << "seed " << seed << ", " << rounds << " rounds";
    }
  }
  EXPECT_GT(multi_round_cases, 20) << "the later rounds were never exercised";
}

}  // namespace
}  // namespace tetrefine::refine_internal

namespace tetrefine::refine_internal {
namespace {

uint32_t PatternOf(const Jittered& box, const FillLater<uint8_t>& split, uint32_t t) {
  uint32_t pattern = 0;
  for (int k = 0; k < 6; ++k) pattern |= split[box.edges.tet_edges[t][k]] != 0 ? EdgeBit(k) : 0u;
  return pattern;
}

std::array<Vec3, 4> CornersOf(const Mesh& mesh, uint32_t t) {
  const Tet& tet = mesh.tets[t];
  return {mesh.points[tet[0]], mesh.points[tet[1]], mesh.points[tet[2]], mesh.points[tet[3]]};
}

// The guard's last look, one flagged tet at a time (a visit list of one): its remedy gives it a
// split at its threshold, and every tet around the added edges keeps a split at its own threshold
// or no worse than before. Over all flagged tets at once there are fewer bad splits after the
// pass than before.
TEST(EdgeMarkingTest, FinalGuardPassRemediesSpareTheNeighbours) {
  constexpr double kRatio = 0.6, kFloor = 0.3;
  const std::function<bool()> never = [] { return false; };
  CancelFlag running(never);
  int remedied = 0, refused = 0, neighbours_changed = 0, fewer_after = 0;
  for (uint32_t seed : {1u, 2u, 3u}) {
    Lcg next{seed};
    const Jittered box = JitteredBox({6.0, 5.0, 4.0}, {6, 5, 4}, next);
    const auto& tets = box.mesh.tets;
    const TetsAround around(tets, static_cast<int64_t>(box.mesh.points.size()));
    for (double density : {0.03, 0.15}) {
      FillLater<uint8_t> start(static_cast<size_t>(box.edges.size()), 0);
      for (int64_t e = 0; e < box.edges.size(); ++e) start[e] = next() < density ? 1 : 0;
      const auto threshold_of = [&](uint32_t t) {
        const auto c = CornersOf(box.mesh, t);
        return std::max(kRatio * MeanRatio(c[0], c[1], c[2], c[3]), kFloor);
      };
      const auto worst_of = [&](const FillLater<uint8_t>& split, uint32_t t) {
        return WorstChildOf(PatternOf(box, split, t), CornersOf(box.mesh, t));
      };
      const auto is_bad = [&](const FillLater<uint8_t>& split, uint32_t t) {
        const uint32_t q = PatternOf(box, split, t);
        return q != 0 && q != 63 && worst_of(split, t) < threshold_of(t);
      };
      int bad_before = 0;
      for (uint32_t t = 0; t < tets.size(); ++t) {
        if (!is_bad(start, t)) continue;
        ++bad_before;
        FillLater<uint8_t> split = start;
        const std::vector<uint32_t> visit = {t};
        if (FinalGuardPass(box.mesh.points, tets, box.edges, around, kRatio, kFloor, split, running,
                           &visit, nullptr) == 0) {
          ++refused;
          continue;
        }
        ++remedied;
        EXPECT_GE(worst_of(split, t), threshold_of(t)) << "tet " << t;
        for (uint32_t s = 0; s < tets.size(); ++s) {
          if (s == t || PatternOf(box, split, s) == PatternOf(box, start, s)) continue;
          ++neighbours_changed;
          const double after = worst_of(split, s);
          EXPECT_TRUE(after >= threshold_of(s) || after >= worst_of(start, s))
              << "tet " << t << "'s remedy made neighbour " << s << "'s split worse: " << after;
        }
      }
      FillLater<uint8_t> all = start;
      FinalGuardPass(box.mesh.points, tets, box.edges, around, kRatio, kFloor, all, running,
                     nullptr, nullptr);
      int bad_after = 0;
      for (uint32_t t = 0; t < tets.size(); ++t) bad_after += is_bad(all, t);
      EXPECT_LE(bad_after, bad_before) << "seed " << seed << ", density " << density;
      fewer_after += bad_after < bad_before;
    }
  }
  // Not a formality: both outcomes, and remedies that reach other tets.
  EXPECT_GT(remedied, 50);
  EXPECT_GT(refused, 5);
  EXPECT_GT(neighbours_changed, 100);
  EXPECT_GE(fewer_after, 4);
}

}  // namespace
}  // namespace tetrefine::refine_internal
