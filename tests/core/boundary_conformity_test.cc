// The conformity check (core/boundary_conformity.h): random conformal meshes pass, and each kind
// of non-conformity (a hanging node on an edge or in a face, a crack, two bodies touching with
// duplicated vertices) is refused with the vertex or edge named.
#include "core/boundary_conformity.h"

#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <random>
#include <string>

#include "absl/strings/str_cat.h"
#include "core/five_tet_cell.h"
#include "core/mesh_validation.h"
#include "core/refine.h"
#include "tests/support/geometry.h"
#include "tests/support/mesh_checks.h"

namespace tetrefine {
namespace {

// FiveTetMesh of [0, n]^3 with every interior vertex moved by up to 0.15 per axis: the tets stay
// positive (checked) and no two faces are coplanar by accident.
Mesh JitteredCube(std::mt19937_64& rng, int n) {
  Mesh m = testing::FiveTetMesh({0, 0, 0}, {double(n), double(n), double(n)}, {n, n, n});
  std::uniform_real_distribution<double> jitter(-0.15, 0.15);
  for (Vec3& p : m.points) {
    const bool interior = std::all_of(p.begin(), p.end(), [&](double x) { return x > 0 && x < n; });
    if (!interior) continue;
    for (double& x : p) x += jitter(rng);
  }
  for (const Tet& t : m.tets) {
    EXPECT_GT(SignedVolume6(m.points[t[0]], m.points[t[1]], m.points[t[2]], m.points[t[3]]), 0.0);
  }
  return m;
}

absl::Status Check(const Mesh& m) { return CheckConformity(m.points, m.tets); }

// How many tets have both u and v.
int TetsOnEdge(const Mesh& m, uint32_t u, uint32_t v) {
  return static_cast<int>(std::count_if(m.tets.begin(), m.tets.end(), [&](const Tet& t) {
    return std::find(t.begin(), t.end(), u) != t.end() &&
           std::find(t.begin(), t.end(), v) != t.end();
  }));
}

// The tets with all of face's vertices.
std::vector<int64_t> TetsOn(const Mesh& m, const std::array<uint32_t, 3>& face) {
  std::vector<int64_t> on;
  for (size_t t = 0; t < m.tets.size(); ++t) {
    if (std::all_of(face.begin(), face.end(), [&](uint32_t v) {
          return std::find(m.tets[t].begin(), m.tets[t].end(), v) != m.tets[t].end();
        })) {
      on.push_back(static_cast<int64_t>(t));
    }
  }
  return on;
}

void ExpectNamed(const absl::Status& s, const std::string& fragment) {
  EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument) << s;
  EXPECT_NE(s.message().find("mesh is not conformal: "), std::string::npos) << s;
  EXPECT_NE(s.message().find(fragment), std::string::npos) << "want '" << fragment << "' in " << s;
}

TEST(BoundaryConformity, RandomConformalMeshesPass) {
  for (uint64_t seed : testing::Seeds(20)) {
    std::printf("seed %llu\n", static_cast<unsigned long long>(seed));
    std::mt19937_64 rng(seed);
    const Mesh m = JitteredCube(rng, 2 + static_cast<int>(seed % 4));
    EXPECT_TRUE(Check(m).ok()) << Check(m);
  }
}

// Split one tet 1:2 at the midpoint of an edge it shares with another tet, and leave that
// neighbour whole: the midpoint hangs on the neighbour's face.
TEST(BoundaryConformity, EdgeHangingNodeIsNamed) {
  for (uint64_t seed : testing::Seeds(20)) {
    std::printf("seed %llu\n", static_cast<unsigned long long>(seed));
    std::mt19937_64 rng(seed);
    Mesh m = JitteredCube(rng, 2 + static_cast<int>(seed % 3));
    const size_t t = rng() % m.tets.size();
    const Tet tet = m.tets[t];
    int i = 0, j = 1;
    for (int tries = 0; tries < 100; ++tries) {
      i = static_cast<int>(rng() % 4);
      j = (i + 1 + static_cast<int>(rng() % 3)) % 4;
      if (TetsOnEdge(m, tet[i], tet[j]) >= 2) break;
    }
    ASSERT_GE(TetsOnEdge(m, tet[i], tet[j]), 2);
    const Vec3& a = m.points[tet[i]];
    const Vec3& b = m.points[tet[j]];
    const auto mid = static_cast<uint32_t>(m.points.size());
    m.points.push_back({0.5 * (a[0] + b[0]), 0.5 * (a[1] + b[1]), 0.5 * (a[2] + b[2])});
    Tet first = tet, second = tet;
    first[j] = mid;
    second[i] = mid;
    m.tets[t] = first;
    m.tets.push_back(second);
    ASSERT_TRUE(CheckFaces(m.points, m.tets).ok()) << "the face check cannot see it";
    ExpectNamed(Check(m), absl::StrCat("vertex ", mid, " at "));
  }
}

// Split one tet 1:3 at the centroid of a face it shares with a neighbour left whole.
TEST(BoundaryConformity, FaceHangingNodeIsNamed) {
  for (uint64_t seed : testing::Seeds(20)) {
    std::printf("seed %llu\n", static_cast<unsigned long long>(seed));
    std::mt19937_64 rng(seed);
    Mesh m = JitteredCube(rng, 2 + static_cast<int>(seed % 3));
    size_t t = 0;
    int skip = 0;
    for (int tries = 0; tries < 1000; ++tries) {
      t = rng() % m.tets.size();
      skip = static_cast<int>(rng() % 4);
      std::array<uint32_t, 3> face;
      for (int k = 0, n = 0; k < 4; ++k) {
        if (k != skip) face[n++] = m.tets[t][k];
      }
      if (TetsOn(m, face).size() == 2) break;
    }
    const Tet tet = m.tets[t];
    Vec3 centroid = {0, 0, 0};
    for (int k = 0; k < 4; ++k) {
      if (k == skip) continue;
      for (int a = 0; a < 3; ++a) centroid[a] += m.points[tet[k]][a] / 3.0;
    }
    const auto c = static_cast<uint32_t>(m.points.size());
    m.points.push_back(centroid);
    bool first = true;
    for (int k = 0; k < 4; ++k) {
      if (k == skip) continue;
      Tet child = tet;
      child[k] = c;
      if (first) {
        m.tets[t] = child;
        first = false;
      } else {
        m.tets.push_back(child);
      }
    }
    ASSERT_TRUE(CheckFaces(m.points, m.tets).ok()) << "the face check cannot see it";
    ExpectNamed(Check(m), absl::StrCat("vertex ", c, " at "));
  }
}

// A crack: the tets on one side of an interior face get their own copies of its vertices, so
// the face exists twice, as two coincident boundary faces.
TEST(BoundaryConformity, CrackIsRefused) {
  for (uint64_t seed : testing::Seeds(10)) {
    std::printf("seed %llu\n", static_cast<unsigned long long>(seed));
    std::mt19937_64 rng(seed);
    Mesh m = JitteredCube(rng, 3);
    const size_t t = rng() % m.tets.size();
    const int keep = static_cast<int>(rng() % 4);
    std::map<uint32_t, uint32_t> copy;
    for (int k = 0; k < 4; ++k) {
      if (k == keep) continue;
      copy[m.tets[t][k]] = static_cast<uint32_t>(m.points.size());
      m.points.push_back(m.points[m.tets[t][k]]);
      m.tets[t][k] = copy[m.tets[t][k]];
    }
    ASSERT_TRUE(CheckFaces(m.points, m.tets).ok());
    ExpectNamed(Check(m), "lies on boundary face");
  }
}

TEST(BoundaryConformity, CubeWithCavityAndSeparateComponentsPass) {
  for (uint64_t seed : testing::Seeds(5)) {
    std::mt19937_64 rng(seed);
    Mesh m = JitteredCube(rng, 4);
    // Drop the 2 x 2 x 2 cells in the middle: a cubic cavity. FiveTetMesh writes 5 tets per cell,
    // cell (i, j, k) at 5 * (i + 4 * (j + 4 * k)).
    std::vector<Tet> kept;
    for (size_t t = 0; t < m.tets.size(); ++t) {
      const size_t cell = t / 5;
      const size_t i = cell % 4, j = cell / 4 % 4, k = cell / 16;
      const bool middle = i >= 1 && i <= 2 && j >= 1 && j <= 2 && k >= 1 && k <= 2;
      if (!middle) kept.push_back(m.tets[t]);
    }
    ASSERT_EQ(kept.size(), m.tets.size() - 40);
    m.tets = kept;
    EXPECT_TRUE(Check(m).ok()) << Check(m);
    // A second, disjoint copy of it, shifted by more than its size.
    const auto n = static_cast<uint32_t>(m.points.size());
    const size_t tets = m.tets.size();
    for (uint32_t v = 0; v < n; ++v) {
      Vec3 p = m.points[v];
      p[0] += 4.5;
      m.points.push_back(p);
    }
    for (size_t t = 0; t < tets; ++t) {
      Tet q = m.tets[t];
      for (uint32_t& v : q) v += n;
      m.tets.push_back(q);
    }
    EXPECT_TRUE(Check(m).ok()) << Check(m);
  }
}

// The real Delaunay mesh passes, where it is and scaled into a millimetre box far from the
// origin (where the tolerance's rounding term is largest), and a hanging node in it is found.
TEST(BoundaryConformity, RealMeshPasses) {
  Mesh m = testing::ReadMeditForTest(std::string(TETREFINE_SHARED_DATA_DIR) +
                                     "/unit_cube_1782tets.mesh");
  ASSERT_EQ(m.tets.size(), 1782u);
  for (const Tet& t : m.tets) {
    ASSERT_GT(SignedVolume6(m.points[t[0]], m.points[t[1]], m.points[t[2]], m.points[t[3]]), 0.0);
  }
  EXPECT_TRUE(Check(m).ok()) << Check(m);
  Mesh far = m;
  for (Vec3& p : far.points) {
    for (double& x : p) x = 3000.0 + 7.3 * x;
  }
  EXPECT_TRUE(Check(far).ok()) << Check(far);
  size_t t = 0;
  while (TetsOnEdge(far, far.tets[t][0], far.tets[t][1]) < 2) ++t;
  const Tet tet = far.tets[t];
  const Vec3& a = far.points[tet[0]];
  const Vec3& b = far.points[tet[1]];
  const auto mid = static_cast<uint32_t>(far.points.size());
  far.points.push_back({0.5 * (a[0] + b[0]), 0.5 * (a[1] + b[1]), 0.5 * (a[2] + b[2])});
  far.tets[t] = {mid, tet[1], tet[2], tet[3]};
  far.tets.push_back({tet[0], mid, tet[2], tet[3]});
  ExpectNamed(Check(far), absl::StrCat("vertex ", mid, " at "));
}

// Two cubes side by side with matching faces but each with its own vertices: the face between
// them is there twice, as boundary faces of both.
TEST(BoundaryConformity, CubesTouchingWithDuplicatedVerticesAreRefused) {
  Mesh m = testing::FiveTetMesh({0, 0, 0}, {2, 2, 2}, {2, 2, 2});
  const Mesh right = testing::FiveTetMesh({2, 0, 0}, {4, 2, 2}, {2, 2, 2});
  const auto n = static_cast<uint32_t>(m.points.size());
  m.points.insert(m.points.end(), right.points.begin(), right.points.end());
  for (Tet q : right.tets) {
    for (uint32_t& v : q) v += n;
    m.tets.push_back(q);
  }
  ASSERT_TRUE(CheckFaces(m.points, m.tets).ok());
  // Vertex 2 is (2, 0, 0), a corner of the right cube's face at x = 2.
  ExpectNamed(Check(m), "vertex 2 at (2, 0, 0) lies on boundary face (");
  // Shifted apart by a hair more than the tolerance, they are two separate bodies.
  for (uint32_t v = n; v < m.points.size(); ++v) m.points[v][0] += 1e-9;
  EXPECT_TRUE(Check(m).ok()) << Check(m);
}

// Two boundary faces with the same three vertices on the same side are two tets overlapping:
// the face check refuses them before the conformity check runs.
TEST(BoundaryConformity, SameFaceTwiceOnOneSideIsAnOverlap) {
  Mesh m;
  m.points = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {0.2, 0.2, 0.5}};
  m.tets = {{0, 1, 2, 3}, {0, 1, 2, 4}};
  const absl::Status s = Check(m);
  EXPECT_NE(s.message().find("overlap"), std::string::npos) << s;
}

// Far from the origin the tolerance grows with the coordinates' rounding; a sliver whose fourth
// vertex then comes within it of the tet's own boundary face is still a valid tet.
TEST(BoundaryConformity, SliverOnItsOwnFacePasses) {
  Mesh m;
  const double o = 1e6;
  m.points = {{o, o, o}, {o + 1, o, o}, {o, o + 1, o}, {o + 0.3, o + 0.3, o + 1e-10}};
  m.tets = {{0, 1, 2, 3}};
  ASSERT_GT(SignedVolume6(m.points[0], m.points[1], m.points[2], m.points[3]), 0.0);
  EXPECT_TRUE(Check(m).ok()) << Check(m);
  // The same vertex as a separate body's, on the face: a hanging node.
  m.points.push_back(m.points[3]);
  m.points.push_back({o + 0.3, o + 0.3, o + 1});
  m.points.push_back({o + 1, o + 0.3, o + 1});
  m.points.push_back({o + 0.3, o + 1, o + 1});
  m.tets.push_back({4, 5, 6, 7});
  if (SignedVolume6(m.points[4], m.points[5], m.points[6], m.points[7]) < 0) {
    std::swap(m.tets[1][2], m.tets[1][3]);
  }
  ExpectNamed(Check(m), "vertex 3 at ");
}

// verify runs the check on any finite coordinates, not only those ValidateMesh lets through:
// near the double range the arithmetic overflows, and the check must still return.
TEST(BoundaryConformity, HugeCoordinatesDoNotBreakIt) {
  for (double scale : {1e200, 1e300, -1e306}) {
    Mesh m = testing::FiveTetMesh({0, 0, 0}, {2, 2, 2}, {2, 2, 2});
    for (Vec3& p : m.points) {
      for (double& x : p) x *= scale;
    }
    if (scale < 0) {
      for (Tet& t : m.tets) std::swap(t[2], t[3]);
    }
    const absl::Status s = Check(m);
    EXPECT_TRUE(s.ok() || s.code() == absl::StatusCode::kInvalidArgument) << s;
  }
}

// A uniformly random rotation, scaled and moved: coplanar faces stay coplanar only up to
// rounding, as in real files.
Mesh RandomlyPlaced(std::mt19937_64& rng, Mesh m) {
  const Mat3 r = testing::RandomRotation(rng);
  std::uniform_real_distribution<double> log_scale(-3.0, 3.0), shift(-1e3, 1e3);
  const double scale = std::pow(10.0, log_scale(rng));
  const Vec3 t = {shift(rng), shift(rng), shift(rng)};
  for (Vec3& p : m.points) {
    const Vec3 o = p;
    for (int i = 0; i < 3; ++i) {
      p[i] = t[i] + scale * (r[3 * i] * o[0] + r[3 * i + 1] * o[1] + r[3 * i + 2] * o[2]);
    }
  }
  return m;
}

// The paper's five-tet split of an n^3 grid with one interior-adjacent cell split the other way:
// each square face it shares with a neighbour is cut by crossing diagonals on its two sides. No
// vertex hangs and every boundary edge is used twice, so only the fold check can see it; the
// same mesh without the flip, placed the same way, passes.
TEST(BoundaryConformity, CrossingDiagonalsAreRefused) {
  for (uint64_t seed : testing::Seeds(20)) {
    std::printf("seed %llu\n", static_cast<unsigned long long>(seed));
    std::mt19937_64 rng(seed);
    const int n = 2 + static_cast<int>(seed % 3);
    Mesh m = testing::FiveTetMesh({0, 0, 0}, {double(n), double(n), double(n)}, {n, n, n});
    const int i = static_cast<int>(rng() % n), j = static_cast<int>(rng() % n),
              k = static_cast<int>(rng() % n);
    const uint32_t np = static_cast<uint32_t>(n + 1);
    auto id = [&](int x, int y, int z) { return static_cast<uint32_t>(x + np * (y + np * z)); };
    std::array<uint32_t, 8> corner;
    for (int b = 0; b < 8; ++b) corner[b] = id(i + (b & 1), j + ((b >> 1) & 1), k + ((b >> 2) & 1));
    std::vector<Tet> flipped;
    AppendFiveTetCell(corner, (i + j + k) % 2 != 0, m.points, &flipped);
    const size_t first = 5 * static_cast<size_t>(i + n * (j + n * k));
    const uint64_t placement = rng();
    std::mt19937_64 place_rng(placement);
    const Mesh conformal = RandomlyPlaced(place_rng, m);
    EXPECT_TRUE(Check(conformal).ok()) << Check(conformal);
    std::copy(flipped.begin(), flipped.end(), m.tets.begin() + static_cast<std::ptrdiff_t>(first));
    place_rng.seed(placement);
    const Mesh crossed = RandomlyPlaced(place_rng, m);
    ASSERT_TRUE(CheckFaces(crossed.points, crossed.tets).ok()) << "the face check cannot see it";
    ExpectNamed(Check(crossed), "lie in one plane on the same side of their common edge");
  }
}

// Two cubes side by side, each split alone, so the square face between them has different
// diagonals on its two sides; ValidateMesh (what refine and verify run) names both faces.
TEST(BoundaryConformity, CrossingDiagonalsNameBothFaces) {
  Mesh m = testing::FiveTetMesh({0, 0, 0}, {1, 1, 1}, {1, 1, 1});
  const Mesh right = testing::FiveTetMesh({1, 0, 0}, {2, 1, 1}, {1, 1, 1});
  std::map<std::array<double, 3>, uint32_t> ids;
  for (uint32_t v = 0; v < m.points.size(); ++v) ids[m.points[v]] = v;
  std::vector<uint32_t> remap;
  for (const Vec3& p : right.points) {
    auto [it, added] = ids.emplace(p, static_cast<uint32_t>(m.points.size()));
    if (added) m.points.push_back(p);
    remap.push_back(it->second);
  }
  for (Tet t : right.tets) {
    for (uint32_t& v : t) v = remap[v];
    m.tets.push_back(t);
  }
  ASSERT_EQ(m.points.size(), 12u);
  ASSERT_TRUE(CheckFaces(m.points, m.tets).ok());
  const absl::Status s = Check(m);
  ExpectNamed(s, "boundary faces (");
  ExpectNamed(s, "crossing");
}

// Two bodies glued at a quadrilateral (a, b, c, d) that is not planar (c lifted by `lift`),
// split along a-c below and b-d above: each body is two tets on an apex. Lifted up, the a-c
// side bulges into the b-d side and the bodies overlap in the tet (a, b, c, d); lifted down they
// bulge apart and leave that tet as a cavity. Placed by `rng`; tets positively oriented.
Mesh GluedAtATwistedQuad(std::mt19937_64& rng, double lift) {
  Mesh m;
  m.points = {{0, 0, 0}, {1, 0, 0}, {1, 1, lift}, {0, 1, 0}, {0.5, 0.5, -1}, {0.5, 0.5, 1}};
  m.tets = {{0, 1, 2, 4}, {0, 2, 3, 4}, {0, 1, 3, 5}, {1, 2, 3, 5}};
  m = RandomlyPlaced(rng, m);
  for (Tet& t : m.tets) {
    if (SignedVolume6(m.points[t[0]], m.points[t[1]], m.points[t[2]], m.points[t[3]]) < 0.0) {
      std::swap(t[2], t[3]);
    }
  }
  return m;
}

// Crossing diagonals out of plane: the fold check cannot see them (the faces are not in one
// plane), the shell check can when the bodies overlap. Where they leave a gap, the mesh is two
// bodies with a tet-shaped cavity between them, which is valid.
TEST(BoundaryConformity, TwistedCrossingDiagonalsThatOverlapAreRefused) {
  for (uint64_t seed : testing::Seeds(20)) {
    SCOPED_TRACE(::testing::Message() << "seed " << seed);
    std::mt19937_64 rng(seed);
    const double lift = std::uniform_real_distribution<double>(0.01, 0.5)(rng);
    const uint64_t placement = rng();
    std::mt19937_64 place(placement);
    const Mesh overlap = GluedAtATwistedQuad(place, lift);
    ASSERT_TRUE(CheckFaces(overlap.points, overlap.tets).ok()) << "the face check cannot see it";
    ExpectNamed(Check(overlap), "reaches out through the others, so two tets overlap");
    place.seed(placement);
    const Mesh gap = GluedAtATwistedQuad(place, -lift);
    EXPECT_TRUE(Check(gap).ok()) << Check(gap);
  }
}

// A shell of four boundary faces may hold tets of its own: a lone tet split at an inner point.
TEST(BoundaryConformity, ATetSplitAtAnInnerPointAlonePasses) {
  for (uint64_t seed : testing::Seeds(10)) {
    std::mt19937_64 rng(seed);
    Mesh m;
    m.points = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {0.2, 0.3, 0.1}};
    m.tets = {{4, 1, 2, 3}, {0, 4, 2, 3}, {0, 1, 4, 3}, {0, 1, 2, 4}};
    m = RandomlyPlaced(rng, m);
    for (Tet& t : m.tets) {
      if (SignedVolume6(m.points[t[0]], m.points[t[1]], m.points[t[2]], m.points[t[3]]) < 0.0) {
        std::swap(t[2], t[3]);
      }
    }
    EXPECT_TRUE(Check(m).ok()) << Check(m);
  }
}

// The verdict and the message do not depend on the thread count.
TEST(BoundaryConformity, SameMessageForAnyThreadCount) {
  for (uint64_t seed : testing::Seeds(5)) {
    std::mt19937_64 rng(seed);
    Mesh m = JitteredCube(rng, 12);
    // Hanging nodes in many places, so that several blocks find one.
    for (int h = 0; h < 20; ++h) {
      const size_t t = rng() % m.tets.size();
      const Tet tet = m.tets[t];
      const Vec3& a = m.points[tet[0]];
      const Vec3& b = m.points[tet[1]];
      const auto mid = static_cast<uint32_t>(m.points.size());
      m.points.push_back({0.5 * (a[0] + b[0]), 0.5 * (a[1] + b[1]), 0.5 * (a[2] + b[2])});
      m.tets[t] = {mid, tet[1], tet[2], tet[3]};
      m.tets.push_back({tet[0], mid, tet[2], tet[3]});
    }
    std::string one;
    tbb::task_arena(1).execute([&] { one = std::string(Check(m).message()); });
    EXPECT_FALSE(one.empty());
    for (int threads : {2, 4}) {
      std::string many;
      tbb::task_arena(threads).execute([&] { many = std::string(Check(m).message()); });
      EXPECT_EQ(one, many);
    }
  }
}

// ValidateMesh, and so Refine, refuses a hanging node with the same message.
TEST(BoundaryConformity, RefineRefusesAHangingNode) {
  std::mt19937_64 rng(7);
  Mesh m = JitteredCube(rng, 2);
  // A tet with an edge (0, 1) that another tet shares.
  size_t t = 0;
  while (TetsOnEdge(m, m.tets[t][0], m.tets[t][1]) < 2) ++t;
  const Tet tet = m.tets[t];
  const Vec3& a = m.points[tet[0]];
  const Vec3& b = m.points[tet[1]];
  const auto mid = static_cast<uint32_t>(m.points.size());
  m.points.push_back({0.5 * (a[0] + b[0]), 0.5 * (a[1] + b[1]), 0.5 * (a[2] + b[2])});
  m.tets[t] = {mid, tet[1], tet[2], tet[3]};
  m.tets.push_back({tet[0], mid, tet[2], tet[3]});
  const absl::Status expected = Check(m);
  ASSERT_FALSE(expected.ok());
  GridGeometry g;
  g.dims = {4, 4, 4};
  const Volume volume = testing::AnalyticVolume(g, [](const Vec3& p) { return p[0]; });
  const absl::StatusOr<RefineResult> r = Refine(volume, m, RefineOptions{});
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.status(), expected);
}

TEST(BoundaryConformity, RefineRefusesTetsOverlappingAcrossATwistedQuad) {
  std::mt19937_64 rng(3);
  Mesh m = GluedAtATwistedQuad(rng, 0.2);
  const absl::Status expected = Check(m);
  ASSERT_FALSE(expected.ok());
  Vec3 lo = m.points[0], hi = m.points[0];
  for (const Vec3& p : m.points) {
    for (int i = 0; i < 3; ++i) lo[i] = std::min(lo[i], p[i]), hi[i] = std::max(hi[i], p[i]);
  }
  GridGeometry g;
  g.dims = {4, 4, 4};
  g.origin = lo;
  for (int i = 0; i < 3; ++i) g.spacing[i] = (hi[i] - lo[i]) / 3.0;
  const Volume volume = testing::AnalyticVolume(g, [](const Vec3& p) { return p[0]; });
  const absl::StatusOr<RefineResult> r = Refine(volume, m, RefineOptions{});
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.status(), expected);
}

}  // namespace
}  // namespace tetrefine

namespace tetrefine {
namespace {

// n thin tets around one edge (0, 1): a valid, conformal mesh whose every boundary face and tet
// meet near the others, as in the review's fan.
Mesh FanAroundAnEdge(int n) {
  Mesh m;
  m.points = {{0, 0, -10}, {0, 0, 25}};
  for (int k = 0; k < n; ++k) {
    const double a = 2.0 * M_PI * k / n;
    m.points.push_back({20.0 * std::cos(a), 20.0 * std::sin(a), 0.0});
  }
  for (int k = 0; k < n; ++k) {
    Tet t = {0, 1, static_cast<uint32_t>(2 + k), static_cast<uint32_t>(2 + (k + 1) % n)};
    const auto& p = m.points;
    if (SignedVolume6(p[t[0]], p[t[1]], p[t[2]], p[t[3]]) < 0) std::swap(t[0], t[1]);
    m.tets.push_back(t);
  }
  return m;
}

// 20,000 slivers around one edge took 6 s in `info` and 60,000 a minute (quadratic in the
// geometric checks: an outside review, 2026-11-28). Such a mesh is refused at once, naming the
// edge, with the same message at any thread count; a fan of a few hundred still passes.
TEST(BoundaryConformity, ACrowdedMeshIsRefusedInBoundedTimeNamingItsEdge) {
  EXPECT_TRUE(CheckConformity(FanAroundAnEdge(300).points, FanAroundAnEdge(300).tets).ok());
  const Mesh fan = FanAroundAnEdge(40000);
  std::string messages[2];
  for (int threads : {1, 2}) {
    tbb::task_arena arena(threads);
    absl::Status s;
    arena.execute([&] { s = CheckConformity(fan.points, fan.tets); });
    ASSERT_EQ(s.code(), absl::StatusCode::kInvalidArgument) << s;
    messages[threads - 1] = std::string(s.message());
  }
  EXPECT_EQ(messages[0], messages[1]);
  EXPECT_NE(messages[0].find("mesh is too crowded to check in bounded time"), std::string::npos)
      << messages[0];
  EXPECT_NE(messages[0].find("the most crowded edge, (0, 1), is shared by 40000 tets"),
            std::string::npos)
      << messages[0];
}

}  // namespace
}  // namespace tetrefine
