// Check 5 of the conformity check: tets that overlap, found from the boundary's owners, and the
// separating-axis depth it rests on.
#include "core/tet_overlap.h"

#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include "core/mesh_validation.h"
#include "core/refine.h"
#include "tests/support/geometry.h"

namespace tetrefine {
namespace {

using Corners4 = std::array<Vec3, 4>;

const Corners4 kUnitTet = {Vec3{0, 0, 0}, Vec3{1, 0, 0}, Vec3{0, 1, 0}, Vec3{0, 0, 1}};

// `t` rotated, scaled by 10^[-3, 3] and moved up to `far` from the origin, the same motion for
// every call with the same `motion` seed.
Corners4 Moved(uint64_t motion, const Corners4& t, double far) {
  std::mt19937_64 rng(motion);
  const Mat3 r = testing::RandomRotation(rng);
  const double scale = std::pow(10.0, std::uniform_real_distribution<double>(-3, 3)(rng));
  std::uniform_real_distribution<double> shift(-far, far);
  const Vec3 o = {shift(rng), shift(rng), shift(rng)};
  Corners4 out;
  for (int k = 0; k < 4; ++k) {
    for (int i = 0; i < 3; ++i) {
      out[k][i] =
          o[i] + scale * (r[3 * i] * t[k][0] + r[3 * i + 1] * t[k][1] + r[3 * i + 2] * t[k][2]);
    }
  }
  return out;
}

Corners4 Scaled(const Corners4& t, double s, const Vec3& shift) {
  Corners4 out;
  for (int k = 0; k < 4; ++k) {
    for (int i = 0; i < 3; ++i) out[k][i] = s * t[k][i] + shift[i];
  }
  return out;
}

TEST(TetOverlapDepth, NeighboursAndSeparatedTetsDoNotOverlap) {
  const std::vector<Corners4> apart = {
      // The unit tet's face x + y + z = 1 shared from the other side.
      {Vec3{1, 0, 0}, Vec3{0, 1, 0}, Vec3{0, 0, 1}, Vec3{1, 1, 1}},
      // Sharing the edge (0,0,0)-(1,0,0) only, below the xy plane.
      {Vec3{0, 0, 0}, Vec3{1, 0, 0}, Vec3{0.3, -1, -0.5}, Vec3{0.5, 0.2, -1}},
      // Sharing the corner at the origin only: the tet mirrored through it.
      {Vec3{0, 0, 0}, Vec3{-1, 0, 0}, Vec3{0, -1, 0}, Vec3{0, 0, -1}},
      // Touching the face x = 0 from outside at a point of it, no shared vertex.
      {Vec3{0, 0.2, 0.2}, Vec3{-1, 0, 0}, Vec3{-1, 1, 0}, Vec3{-1, 0, 1}},
      // Far away.
      Scaled(kUnitTet, 1.0, {5, 5, 5}),
  };
  for (uint64_t seed : testing::Seeds(20)) {
    SCOPED_TRACE(::testing::Message() << "seed " << seed);
    for (size_t k = 0; k < apart.size(); ++k) {
      for (double far : {0.0, 1e3, 1e6}) {
        const Corners4 a = Moved(seed, kUnitTet, far), b = Moved(seed, apart[k], far);
        EXPECT_EQ(TetOverlapDepth(a, b), 0.0) << "case " << k << " far " << far;
        EXPECT_EQ(TetOverlapDepth(b, a), 0.0) << "case " << k << " far " << far;
      }
    }
  }
}

TEST(TetOverlapDepth, OverlappingTetsHaveTheirDepth) {
  for (uint64_t seed : testing::Seeds(20)) {
    SCOPED_TRACE(::testing::Message() << "seed " << seed);
    // Identical: as deep as the tet's thinnest width (its height over the slanted face).
    const Corners4 a = Moved(seed, kUnitTet, 1e3);
    const double scale = std::sqrt((a[1][0] - a[0][0]) * (a[1][0] - a[0][0]) +
                                   (a[1][1] - a[0][1]) * (a[1][1] - a[0][1]) +
                                   (a[1][2] - a[0][2]) * (a[1][2] - a[0][2]));
    EXPECT_NEAR(TetOverlapDepth(a, a), scale / std::sqrt(3.0), 1e-9 * scale);
    // A smaller copy inside, and a copy shifted by a third along an edge.
    const Corners4 inside = Moved(seed, Scaled(kUnitTet, 0.25, {0.1, 0.1, 0.1}), 1e3);
    EXPECT_GT(TetOverlapDepth(a, inside), 0.0);
    EXPECT_GT(TetOverlapDepth(inside, a), 0.0);
    const Corners4 shifted = Moved(seed, Scaled(kUnitTet, 1.0, {1.0 / 3, 0, 0}), 1e3);
    EXPECT_GT(TetOverlapDepth(a, shifted), 0.0);
    // The shared face's neighbour pushed in across it by 1e-6 of the size overlaps; by 1e-13,
    // rounding, it does not.
    for (double push : {1e-6, 1e-13}) {
      const double c = 1.0 / 3.0 - push;
      const Corners4 across = {Vec3{1, 0, 0}, Vec3{0, 1, 0}, Vec3{0, 0, 1}, Vec3{c, c, c}};
      const Corners4 b = Moved(seed, Scaled(across, 1.0, {0, 0, 0}), 1e3);
      const Corners4 base = Moved(seed, kUnitTet, 1e3);
      if (push > 1e-9) {
        EXPECT_GT(TetOverlapDepth(base, b), 0.0);
      } else {
        EXPECT_EQ(TetOverlapDepth(base, b), 0.0);
      }
    }
  }
}

// Barycentric coordinates of p in t, by Cramer's rule.
std::array<double, 4> Barycentric(const Corners4& t, const Vec3& p) {
  std::array<double, 4> w;
  const double v = SignedVolume6(t[0], t[1], t[2], t[3]);
  w[0] = SignedVolume6(p, t[1], t[2], t[3]) / v;
  w[1] = SignedVolume6(t[0], p, t[2], t[3]) / v;
  w[2] = SignedVolume6(t[0], t[1], p, t[3]) / v;
  w[3] = SignedVolume6(t[0], t[1], t[2], p) / v;
  return w;
}

// Against sampling: a point of one tet found well inside the other means they overlap; a depth
// of a tenth of their size means sampling finds such a point.
TEST(TetOverlapDepth, AgreesWithSampledPoints) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  int overlapping = 0, apart = 0;
  for (int pair = 0; pair < 400; ++pair) {
    Corners4 a, b;
    for (Corners4* t : {&a, &b}) {
      do {
        for (Vec3& p : *t) p = {u(rng), u(rng), u(rng)};
      } while (std::abs(SignedVolume6((*t)[0], (*t)[1], (*t)[2], (*t)[3])) < 0.05);
    }
    const double depth = TetOverlapDepth(a, b);
    bool common = false;
    for (int s = 0; s < 20000 && !common; ++s) {
      double w[4], sum = 0.0;
      for (double& x : w) sum += (x = -std::log(u(rng)));
      Vec3 p{0, 0, 0};
      for (int k = 0; k < 4; ++k) {
        for (int i = 0; i < 3; ++i) p[i] += w[k] / sum * a[k][i];
      }
      const std::array<double, 4> in_b = Barycentric(b, p);
      common = *std::min_element(in_b.begin(), in_b.end()) > 1e-9;
    }
    if (common) {
      EXPECT_GT(depth, 0.0) << "pair " << pair;
    }
    if (depth > 0.1) {
      EXPECT_TRUE(common) << "pair " << pair << " depth " << depth;
    }
    (depth > 0.0 ? overlapping : apart) += 1;
  }
  // Both verdicts were exercised.
  EXPECT_GT(overlapping, 50);
  EXPECT_GT(apart, 50);
}

Mesh OverlapCube(std::mt19937_64& rng, int n, const Vec3& at, double size) {
  Mesh m = testing::FiveTetMesh(at, {at[0] + size, at[1] + size, at[2] + size}, {n, n, n});
  std::uniform_real_distribution<double> jitter(-0.15 * size / n, 0.15 * size / n);
  for (Vec3& p : m.points) {
    bool interior = true;
    for (int i = 0; i < 3; ++i) interior = interior && p[i] > at[i] && p[i] < at[i] + size;
    if (!interior) continue;
    for (double& x : p) x += jitter(rng);
  }
  return m;
}

// b's points and tets appended to a's, with their own vertex ids.
Mesh Together(Mesh a, const Mesh& b) {
  const auto n = static_cast<uint32_t>(a.points.size());
  a.points.insert(a.points.end(), b.points.begin(), b.points.end());
  for (Tet t : b.tets) {
    for (uint32_t& v : t) v += n;
    a.tets.push_back(t);
  }
  return a;
}

void ExpectOverlap(const absl::Status& s) {
  EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument) << s;
  EXPECT_NE(s.message().find("mesh is not conformal: mesh.tets["), std::string::npos) << s;
  EXPECT_NE(s.message().find("overlap (their interiors intersect"), std::string::npos) << s;
}

// A mesh inside another shares no vertex, edge or face with it and leaves both boundaries
// closed: every earlier check passes it.
TEST(TetOverlap, AMeshInsideAnotherIsRefused) {
  for (uint64_t seed : testing::Seeds(10)) {
    SCOPED_TRACE(::testing::Message() << "seed " << seed);
    std::mt19937_64 rng(seed);
    const Mesh outer = OverlapCube(rng, 3, {0, 0, 0}, 3.0);
    ASSERT_TRUE(CheckConformity(outer.points, outer.tets).ok());
    const Mesh inner = OverlapCube(rng, 2, {0.71, 0.93, 1.13}, 1.1);
    const Mesh both = Together(outer, inner);
    ASSERT_TRUE(CheckFaces(both.points, both.tets).ok());
    ExpectOverlap(CheckConformity(both.points, both.tets));
    // One lone tet inside a tet of the mesh.
    Mesh lone = outer;
    const Tet& host = outer.tets[rng() % outer.tets.size()];
    Vec3 c{0, 0, 0};
    for (uint32_t v : host) {
      for (int i = 0; i < 3; ++i) c[i] += 0.25 * outer.points[v][i];
    }
    const auto base = static_cast<uint32_t>(lone.points.size());
    for (const Vec3& p : kUnitTet) {
      lone.points.push_back({c[0] + 0.05 * p[0], c[1] + 0.05 * p[1], c[2] + 0.05 * p[2]});
    }
    lone.tets.push_back({base, base + 1, base + 2, base + 3});
    ExpectOverlap(CheckConformity(lone.points, lone.tets));
    // The same inner mesh beside the outer one, not in it, passes.
    const Mesh beside = Together(outer, OverlapCube(rng, 2, {3.5, 0.93, 1.13}, 1.1));
    EXPECT_TRUE(CheckConformity(beside.points, beside.tets).ok());
  }
}

TEST(TetOverlap, TwoMeshesOverlappingInPartAreRefused) {
  for (uint64_t seed : testing::Seeds(10)) {
    SCOPED_TRACE(::testing::Message() << "seed " << seed);
    std::mt19937_64 rng(seed);
    const Mesh a = OverlapCube(rng, 3, {0, 0, 0}, 1.0);
    const double dx = std::uniform_real_distribution<double>(0.3, 0.9)(rng);
    const Mesh b = OverlapCube(rng, 3, {dx, 0.137, -0.211}, 1.0);
    ExpectOverlap(CheckConformity(Together(a, b).points, Together(a, b).tets));
  }
}

// A hexagon whose corners go up and down, triangulated one way as the floor of a cone of tets
// above it and another way as the roof of a cone below it. Where the two triangulations
// differ, the surfaces part: above-below means a cavity (valid), below-above an overlap of the
// two bodies, along a region as large as the hexagon, not one quadrilateral.
struct Hexagon {
  std::array<Vec3, 6> corners;
  std::vector<std::array<int, 3>> top, bottom;  // triangles of corner indices
};

// The 14 triangulations of a convex hexagon, each as 4 triangles of corner indices.
std::vector<std::vector<std::array<int, 3>>> Triangulations(std::vector<int> polygon) {
  if (polygon.size() < 3) return {{}};
  if (polygon.size() == 3) return {{{polygon[0], polygon[1], polygon[2]}}};
  std::vector<std::vector<std::array<int, 3>>> all;
  // The triangle on edge (first, last) has apex polygon[k].
  const int first = polygon.front(), last = polygon.back();
  for (size_t k = 1; k + 1 < polygon.size(); ++k) {
    const std::vector<int> left(polygon.begin(), polygon.begin() + k + 1);
    const std::vector<int> right(polygon.begin() + k, polygon.end());
    for (const auto& l : Triangulations(left)) {
      for (const auto& r : Triangulations(right)) {
        std::vector<std::array<int, 3>> t = l;
        t.insert(t.end(), r.begin(), r.end());
        t.push_back({first, polygon[k], last});
        all.push_back(t);
      }
    }
  }
  return all;
}

// Height along the xy segment p-q of the line through corners p and q at the point c, if the
// two xy segments (p, q) and (r, s) cross inside both; the largest of (bottom's height minus
// top's) over the crossings of their diagonals is how far the two surfaces overlap at most (the
// difference of two piecewise linear functions peaks at a crossing or a corner, where it is 0).
double MostOverlap(const Hexagon& h) {
  auto diagonals = [](const std::vector<std::array<int, 3>>& tris) {
    std::vector<std::array<int, 2>> d;
    for (const auto& t : tris) {
      for (int e = 0; e < 3; ++e) {
        int a = t[e], b = t[(e + 1) % 3];
        if (a > b) std::swap(a, b);
        if (b - a != 1 && !(a == 0 && b == 5)) d.push_back({a, b});
      }
    }
    return d;
  };
  double most = 0.0;
  for (const auto& [p, q] : diagonals(h.top)) {
    for (const auto& [r, s] : diagonals(h.bottom)) {
      const Vec3 &P = h.corners[p], &Q = h.corners[q], &R = h.corners[r], &S = h.corners[s];
      const double d1x = Q[0] - P[0], d1y = Q[1] - P[1], d2x = S[0] - R[0], d2y = S[1] - R[1];
      const double den = d1x * d2y - d1y * d2x;
      if (std::abs(den) < 1e-12) continue;
      const double t = ((R[0] - P[0]) * d2y - (R[1] - P[1]) * d2x) / den;
      const double u = ((R[0] - P[0]) * d1y - (R[1] - P[1]) * d1x) / den;
      if (t <= 1e-9 || t >= 1 - 1e-9 || u <= 1e-9 || u >= 1 - 1e-9) continue;
      const double top_z = P[2] + t * (Q[2] - P[2]), bottom_z = R[2] + u * (S[2] - R[2]);
      most = std::max(most, bottom_z - top_z);
    }
  }
  return most;
}

Mesh HexagonBodies(const Hexagon& h) {
  Mesh m;
  m.points.assign(h.corners.begin(), h.corners.end());
  m.points.push_back({0, 0, 3});   // 6: the top cone's apex
  m.points.push_back({0, 0, -3});  // 7: the bottom cone's
  for (const auto& t : h.top) m.tets.push_back({uint32_t(t[0]), uint32_t(t[1]), uint32_t(t[2]), 6});
  for (const auto& t : h.bottom) {
    m.tets.push_back({uint32_t(t[0]), uint32_t(t[1]), uint32_t(t[2]), 7});
  }
  for (Tet& t : m.tets) {
    if (SignedVolume6(m.points[t[0]], m.points[t[1]], m.points[t[2]], m.points[t[3]]) < 0.0) {
      std::swap(t[2], t[3]);
    }
  }
  return m;
}

TEST(TetOverlap, OverlapAcrossADifferentlyTriangulatedHexagonIsRefused) {
  const auto triangulations = Triangulations({0, 1, 2, 3, 4, 5});
  ASSERT_EQ(triangulations.size(), 14u);
  int refused = 0, passed = 0, by_this_check = 0;
  const std::vector<uint64_t> seeds = testing::Seeds(60);
  for (uint64_t seed : seeds) {
    SCOPED_TRACE(::testing::Message() << "seed " << seed);
    std::mt19937_64 rng(seed);
    Hexagon h;
    std::uniform_real_distribution<double> lift(-0.4, 0.4);
    for (int k = 0; k < 6; ++k) {
      const double angle = k * M_PI / 3.0;
      h.corners[k] = {std::cos(angle), std::sin(angle), lift(rng)};
    }
    h.top = triangulations[rng() % 14];
    do {
      h.bottom = triangulations[rng() % 14];
    } while (h.bottom == h.top);
    const Mesh m = HexagonBodies(h);
    ASSERT_TRUE(CheckFaces(m.points, m.tets).ok()) << CheckFaces(m.points, m.tets);
    const double most = MostOverlap(h);
    const absl::Status s = CheckConformity(m.points, m.tets);
    if (most > 1e-3) {
      EXPECT_FALSE(s.ok()) << "overlap up to " << most;
      ++refused;
      if (s.message().find("overlap (their interiors intersect") != std::string::npos) {
        ++by_this_check;
      }
    } else if (most < 1e-12) {
      EXPECT_TRUE(s.ok()) << s;
      ++passed;
    }
  }
  std::printf("refused %d (%d by the overlap check), passed %d\n", refused, by_this_check, passed);
  // Over the usual seeds (not one pinned with TETREFINE_SEED) both verdicts come up, and cases
  // that no quadrilateral shell explains reach this check.
  if (seeds.size() >= 60) {
    EXPECT_GT(refused, 10);
    EXPECT_GT(passed, 3);
    EXPECT_GT(by_this_check, 3);
  }
}

// A boundary graded over a factor 2^12 in face size takes the box tree instead of the grid
// (tet_overlap.cc, SizeSpread): a valid graded mesh passes, and a tet placed inside it among
// its finest tets or its coarsest ones is found.
TEST(TetOverlap, GradedBoundariesStillFindOverlaps) {
  Mesh graded = testing::FiveTetMesh({0, 0, 0}, {36, 36, 36}, {18, 18, 18});
  for (Vec3& p : graded.points) {
    for (double& x : p) x = std::exp2(x / 3.0);
  }
  ASSERT_TRUE(CheckConformity(graded.points, graded.tets).ok());
  for (const Vec3& at : {Vec3{1.3, 1.4, 1.5}, Vec3{2500, 2700, 3100}}) {
    SCOPED_TRACE(::testing::Message() << "inside at " << at[0]);
    Mesh m = graded;
    const auto base = static_cast<uint32_t>(m.points.size());
    const double size = 0.01 * at[0];
    for (const Vec3& p : kUnitTet) {
      m.points.push_back({at[0] + size * p[0], at[1] + size * p[1], at[2] + size * p[2]});
    }
    m.tets.push_back({base, base + 1, base + 2, base + 3});
    ExpectOverlap(CheckConformity(m.points, m.tets));
  }
}

// Most tets are passed over from their corners' cells of the face grid (FaceCellGrid::MayMeet):
// a lone tet anywhere inside a mesh, of any size from a hundredth of a cell to a few cells,
// deep inside or by the boundary, is still found through the tets around it.
TEST(TetOverlap, ALoneTetAnywhereInsideIsFound) {
  std::mt19937_64 rng(29);
  const Mesh outer = OverlapCube(rng, 9, {0, 0, 0}, 9.0);
  ASSERT_TRUE(CheckConformity(outer.points, outer.tets).ok());
  std::uniform_real_distribution<double> where(0.05, 8.95);
  std::uniform_real_distribution<double> log_size(-2.0, 0.5);
  for (int trial = 0; trial < 200; ++trial) {
    const Vec3 at = {where(rng), where(rng), where(rng)};
    const double size =
        std::min(std::pow(10.0, log_size(rng)), 8.99 - std::max({at[0], at[1], at[2]}));
    SCOPED_TRACE(::testing::Message()
                 << "at " << at[0] << " " << at[1] << " " << at[2] << ", size " << size);
    Mesh m = outer;
    const auto base = static_cast<uint32_t>(m.points.size());
    for (const Vec3& p : kUnitTet) {
      m.points.push_back({at[0] + size * p[0], at[1] + size * p[1], at[2] + size * p[2]});
    }
    m.tets.push_back({base, base + 1, base + 2, base + 3});
    ExpectOverlap(CheckConformity(m.points, m.tets));
  }
}

// Found by a sweep (2026-11-28): a valid mesh scaled by 1e80 made `tetrefine verify` abort
// (std::length_error from the overlap check's face grid, sized from face boxes that had
// overflowed to NaN), and an overlap scaled by 1e-90 was reported "inf deep" (its face boxes
// NaN too, which UBSan saw reach a float-to-int cast). Both are refused with a message now; an
// overlap at 1e-25 is still found.
TEST(TetOverlap, MeshesAtExtremeScalesGetAnAnswerNotACrash) {
  for (double scale : {1e31, 1e80, 1e100, 1e300}) {
    SCOPED_TRACE(::testing::Message() << "scale " << scale);
    Mesh m = testing::FiveTetMesh({0, 0, 0}, {5, 5, 5}, {5, 5, 5});
    for (Vec3& p : m.points) {
      for (double& x : p) x *= scale;
    }
    const absl::Status s = CheckConformity(m.points, m.tets);
    EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument) << s;
    EXPECT_NE(s.message().find("is too large: coordinates must lie within +-1e30"),
              std::string::npos)
        << s;
  }
  for (double scale : {1e-25, 1e-35, 1e-80, 1e-90, 1e-100}) {
    SCOPED_TRACE(::testing::Message() << "scale " << scale);
    Mesh m = testing::FiveTetMesh({0, 0, 0}, {3, 3, 3}, {3, 3, 3});
    const auto base = static_cast<uint32_t>(m.points.size());
    for (const Vec3& p : kUnitTet) {
      m.points.push_back({1.3 + 0.2 * p[0], 1.4 + 0.2 * p[1], 1.5 + 0.2 * p[2]});
    }
    m.tets.push_back({base, base + 1, base + 2, base + 3});
    for (Vec3& p : m.points) {
      for (double& x : p) x *= scale;
    }
    const absl::Status s = CheckConformity(m.points, m.tets);
    if (scale > 1e-30) {
      ExpectOverlap(s);
    } else {
      EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument) << s;
      EXPECT_NE(s.message().find("whose edges are all shorter than 1e-30"), std::string::npos) << s;
    }
    EXPECT_EQ(s.message().find("inf"), std::string::npos) << s;
    EXPECT_EQ(s.message().find("nan"), std::string::npos) << s;
  }
}

TEST(TetOverlap, SameMessageForAnyThreadCount) {
  std::mt19937_64 rng(11);
  const Mesh a = OverlapCube(rng, 8, {0, 0, 0}, 1.0);
  const Mesh b = OverlapCube(rng, 8, {0.43, 0.137, -0.211}, 1.0);
  const Mesh m = Together(a, b);
  std::string one;
  tbb::task_arena(1).execute(
      [&] { one = std::string(CheckConformity(m.points, m.tets).message()); });
  EXPECT_FALSE(one.empty());
  for (int threads : {2, 4}) {
    std::string many;
    tbb::task_arena(threads).execute(
        [&] { many = std::string(CheckConformity(m.points, m.tets).message()); });
    EXPECT_EQ(one, many);
  }
}

TEST(TetOverlap, RefineRefusesOverlappingTets) {
  std::mt19937_64 rng(5);
  const Mesh m = Together(OverlapCube(rng, 2, {0, 0, 0}, 3.0), OverlapCube(rng, 1, {1, 1, 1}, 1.0));
  const absl::Status expected = CheckConformity(m.points, m.tets);
  ExpectOverlap(expected);
  GridGeometry g;
  g.dims = {5, 5, 5};
  g.origin = {0, 0, 0};
  g.spacing = {0.75, 0.75, 0.75};
  const Volume volume = testing::AnalyticVolume(g, [](const Vec3& p) { return p[0] * p[1]; });
  const absl::StatusOr<RefineResult> r = Refine(volume, m, RefineOptions{});
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.status(), expected);
}

}  // namespace
}  // namespace tetrefine
