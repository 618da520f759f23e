// CloseAndGuard visits only the tets whose split pattern changed since a rule last saw them; it
// must mark exactly what the full passes mark, round for round. Checked against the plain
// sequence of CloseToLongestEdges and PromoteBadSplits on jittered and refined meshes with random
// marks, for several rule settings and thread counts.

#include "core/marking_sequence.h"

#include <tbb/task_arena.h>

#include <cmath>
#include <cstdint>
#include <functional>
#include <random>
#include <string>
#include <vector>

#include "core/alternative_tilings.h"
#include "core/edge_table.h"
#include "core/refine.h"
#include "core/refine_state.h"
#include "core/subdivision_table.h"
#include "core/tet_topology.h"
#include "core/tets_around.h"
#include "gtest/gtest.h"
#include "tests/support/geometry.h"

namespace tetrefine::refine_internal {
namespace {

struct Case {
  Mesh mesh;
  EdgeTable edges;
};

Case WithEdges(Mesh mesh) {
  Case c{std::move(mesh), {}};
  c.edges = BuildEdgeTable(c.mesh.tets, static_cast<int64_t>(c.mesh.points.size()));
  AddTetEdges(c.mesh.tets, &c.edges);
  return c;
}

// A box of 5-tet cells with every point moved by up to 0.1 per axis.
Case JitteredBox(std::mt19937_64& rng) {
  Mesh mesh = testing::FiveTetMesh({0.0, 0.0, 0.0}, {7.0, 6.0, 5.0}, {7, 6, 5});
  std::uniform_real_distribution<double> jitter(-0.1, 0.1);
  for (Vec3& p : mesh.points) {
    for (double& x : p) x += jitter(rng);
  }
  return WithEdges(std::move(mesh));
}

// A box refined twice by the paper's scheme on a ripple: tets of many shapes and sizes, the
// kind the later iterations of a refinement see.
Case RefinedBox() {
  GridGeometry g;
  g.dims = {24, 24, 24};
  const Volume volume = testing::AnalyticVolume(g, [](const Vec3& p) {
    return 100.0 * std::sin(p[0] * 0.5) * std::cos(p[1] * 0.4) * std::sin(p[2] * 0.3);
  });
  RefineOptions o;
  o.scheme = RefineScheme::kPaper;
  o.epsilon = 0.02;
  o.max_iterations = 2;
  o.lattice_n = 0;
  auto r = Refine(volume, testing::FiveTetMesh({0, 0, 0}, {23, 23, 23}, {4, 4, 4}), o);
  EXPECT_TRUE(r.ok()) << r.status();
  return WithEdges(std::move(r->mesh));
}

FillLater<uint8_t> RandomMarks(const Case& c, double density, std::mt19937_64& rng) {
  FillLater<uint8_t> split(static_cast<size_t>(c.edges.size()), 0);
  std::bernoulli_distribution marked(density);
  for (int64_t e = 0; e < c.edges.size(); ++e) split[e] = marked(rng) ? 1 : 0;
  return split;
}

// The sequence CloseAndGuard stands for, with every pass over every tet.
MarkingCounts FullPasses(const Case& c, const MarkingRules& rules, FillLater<uint8_t>& split,
                         CancelFlag& cancel) {
  MarkingCounts counts;
  FillLater<uint16_t> targets(c.mesh.tets.size(), kTargetsUnknown);
  const auto& p = c.mesh.points;
  const auto& t = c.mesh.tets;
  if (rules.closure_rounds > 0) {
    counts.closure_edges +=
        CloseToLongestEdges(p, t, c.edges, rules.closure_rounds, split, cancel, &targets);
  }
  for (int r = 0; r < rules.guard_rounds; ++r) {
    counts.guard_edges += PromoteBadSplits(p, t, c.edges, rules.guard_ratio, rules.guard_floor,
                                           rules.best_tiling, split, cancel);
    if (rules.closure_rounds > 0) {
      counts.closure_edges +=
          CloseToLongestEdges(p, t, c.edges, rules.closure_rounds, split, cancel, &targets);
    }
  }
  if (rules.final_guard && rules.best_tiling && rules.guard_rounds > 0) {
    const TetsAround around(t, static_cast<int64_t>(p.size()));
    counts.guard_edges += FinalGuardPass(p, t, c.edges, around, rules.guard_ratio,
                                         rules.guard_floor, split, cancel, nullptr, nullptr);
  }
  return counts;
}

// Returns the guard's edges.
int64_t ExpectSameMarks(const Case& c, const FillLater<uint8_t>& start, const MarkingRules& rules,
                        const std::string& what, int* passes_with_work) {
  const std::function<bool()> never = [] { return false; };
  CancelFlag running(never);
  FillLater<uint8_t> expected = start;
  const MarkingCounts want = FullPasses(c, rules, expected, running);
  for (int threads : {1, 2}) {
    FillLater<uint8_t> got = start;
    MarkingCounts have;
    tbb::task_arena arena(threads);
    arena.execute(
        [&] { have = CloseAndGuard(c.mesh.points, c.mesh.tets, c.edges, rules, got, running); });
    EXPECT_EQ(have.closure_edges, want.closure_edges) << what << ", " << threads << " threads";
    EXPECT_EQ(have.guard_edges, want.guard_edges) << what << ", " << threads << " threads";
    EXPECT_TRUE(got == expected) << what << ", " << threads << " threads";
  }
  if (want.guard_edges > 0 && want.closure_edges > 0) ++*passes_with_work;
  return want.guard_edges;
}

TEST(MarkingSequenceTest, MarksWhatTheFullPassesMark) {
  std::mt19937_64 rng(20261125);
  std::vector<Case> cases;
  for (int i = 0; i < 3; ++i) cases.push_back(JitteredBox(rng));
  cases.push_back(RefinedBox());
  int with_work = 0;
  // Settings where the guard's last look added edges to what the passes before it marked.
  int final_guard_work = 0;
  int64_t guard_edges_before = 0;
  for (size_t k = 0; k < cases.size(); ++k) {
    for (double density : {0.002, 0.02, 0.1}) {
      const FillLater<uint8_t> start = RandomMarks(cases[k], density, rng);
      for (int closure_rounds : {0, 1, 2, 8}) {
        for (int guard_rounds : {0, 1, 2, 3}) {
          // The default scheme's ratio, and a stricter one that promotes more (alternating).
          for (double ratio : {k % 2 == 0 ? 0.6 : 0.9}) {
            for (int variant = 0; variant < 3; ++variant) {
              // Without the better tilings; with them; with them and the guard's last look.
              const bool best_tiling = variant > 0;
              const bool final_guard = variant == 2;
              if (final_guard && guard_rounds == 0) continue;
              MarkingRules rules;
              rules.closure_rounds = closure_rounds;
              rules.guard_rounds = guard_rounds;
              rules.guard_ratio = ratio;
              // A floor on every other case: the default scheme's is half the input's worst tet.
              rules.guard_floor = k % 2 == 1 ? 0.0 : 0.4;
              rules.best_tiling = best_tiling;
              rules.final_guard = final_guard;
              const int64_t guard_edges = ExpectSameMarks(
                  cases[k], start, rules,
                  "case " + std::to_string(k) + ", density " + std::to_string(density) +
                      ", closure " + std::to_string(closure_rounds) + ", guard " +
                      std::to_string(guard_rounds) + " x " + std::to_string(ratio) + ", floor " +
                      std::to_string(rules.guard_floor) + (best_tiling ? ", best tiling" : "") +
                      (final_guard ? ", final guard" : ""),
                  &with_work);
              if (final_guard && guard_edges > guard_edges_before) ++final_guard_work;
              guard_edges_before = guard_edges;
            }
          }
        }
      }
    }
  }
  // The comparison means something only where both rules marked edges after the first pass.
  EXPECT_GT(with_work, 100);
  EXPECT_GT(final_guard_work, 50);
}

// The tilings the guard leaves for the subdivision are BestTiling's answers for their own keys,
// and for most guarded tets still the key the subdivision will compute: reusing one is choosing
// again, for less.
TEST(MarkingSequenceTest, GuardTilingsAreBestTilingsAnswers) {
  const std::function<bool()> never = [] { return false; };
  std::mt19937_64 rng(99);
  for (Case c : {JitteredBox(rng), RefinedBox()}) {
    for (bool final_guard : {false, true}) {
      FillLater<uint8_t> split = RandomMarks(c, 0.02, rng);
      MarkingRules rules;
      rules.closure_rounds = 8;
      rules.guard_rounds = 2;
      rules.guard_ratio = 0.6;
      rules.best_tiling = true;
      rules.final_guard = final_guard;
      FillLater<uint16_t> tilings;
      CancelFlag running(never);
      CloseAndGuard(c.mesh.points, c.mesh.tets, c.edges, rules, split, running, &tilings);
      ASSERT_EQ(tilings.size(), c.mesh.tets.size());
      int64_t known = 0, current = 0;
      for (size_t t = 0; t < c.mesh.tets.size(); ++t) {
        if (tilings[t] == kUnknownTiling) continue;
        ++known;
        const Tet& tet = c.mesh.tets[t];
        std::array<Vec3, 10> p;
        for (int k = 0; k < 4; ++k) p[k] = c.mesh.points[tet[k]];
        for (int k = 0; k < 6; ++k) p[4 + k] = Midpoint(p[kTetEdges[k][0]], p[kTetEdges[k][1]]);
        const uint32_t key = tilings[t] & (kNumSubdivisionKeys - 1);
        EXPECT_EQ(BestTiling(key, {p[0], p[1], p[2], p[3]}), tilings[t]) << "tet " << t;
        uint32_t pattern = 0;
        for (int k = 0; k < 6; ++k)
          pattern |= split[c.edges.tet_edges[t][k]] != 0 ? EdgeBit(k) : 0u;
        // The guard saw a pattern the marks only grew from.
        EXPECT_EQ(key & 63u & ~pattern, 0u) << "tet " << t;
        current += SubdivisionKey(pattern, p) == key;
      }
      EXPECT_GT(known, 0);
      EXPECT_GT(current, known / 2) << "the subdivision would reuse few of them";
    }
  }
  MarkingRules no_guard;
  no_guard.closure_rounds = 8;
  no_guard.best_tiling = true;
  std::mt19937_64 rng2(5);
  const Case c = JitteredBox(rng2);
  FillLater<uint8_t> split = RandomMarks(c, 0.02, rng2);
  FillLater<uint16_t> tilings;
  CancelFlag running(never);
  CloseAndGuard(c.mesh.points, c.mesh.tets, c.edges, no_guard, split, running, &tilings);
  EXPECT_TRUE(tilings.empty()) << "without a guard there is nothing to reuse";
}

TEST(MarkingSequenceTest, MarksNothingOnceCancelled) {
  std::mt19937_64 rng(7);
  const Case c = JitteredBox(rng);
  FillLater<uint8_t> split = RandomMarks(c, 0.02, rng);
  const FillLater<uint8_t> before = split;
  const std::function<bool()> always = [] { return true; };
  CancelFlag cancelled(always);
  MarkingRules rules;
  rules.closure_rounds = 8;
  rules.guard_rounds = 2;
  rules.guard_ratio = 0.6;
  const MarkingCounts counts =
      CloseAndGuard(c.mesh.points, c.mesh.tets, c.edges, rules, split, cancelled);
  EXPECT_EQ(counts.closure_edges, 0);
  EXPECT_EQ(counts.guard_edges, 0);
  EXPECT_TRUE(split == before);
}

}  // namespace
}  // namespace tetrefine::refine_internal
