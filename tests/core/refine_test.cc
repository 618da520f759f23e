// Whole meshes through Refine: conformity after every iteration, convergence, determinism
// across threads and vertex numbering, limits, cancellation.
#include "core/refine.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <numeric>
#include <set>
#include <utility>

#include "core/mesh_validation.h"
#include "core/quality.h"
#include "core/refine_options.h"
#include "tests/support/geometry.h"
#include "tests/support/mesh_checks.h"
#include "tests/support/scheme_printer.h"

namespace tetrefine {
namespace {

// A smooth field with features smaller than a coarse tet: a tilted Gaussian blob on a ramp.
struct BlobField {
  Vec3 c;
  double width;
  double operator()(const Vec3& p) const {
    const double d2 = (p[0] - c[0]) * (p[0] - c[0]) + (p[1] - c[1]) * (p[1] - c[1]) +
                      (p[2] - c[2]) * (p[2] - c[2]);
    return 100.0 * std::exp(-d2 / (width * width)) + 0.3 * p[0] - 0.2 * p[2];
  }
};

// Anisotropic voxels as in the paper's heart data.
GridGeometry HeartGrid() {
  GridGeometry g;
  g.dims = {24, 24, 12};
  g.spacing = {2.87, 2.87, 5.74};
  g.origin = {-10.0, 5.0, 1.0};
  return g;
}

Vec3 GridMax(const GridGeometry& g) {
  return {g.origin[0] + (g.dims[0] - 1) * g.spacing[0],
          g.origin[1] + (g.dims[1] - 1) * g.spacing[1],
          g.origin[2] + (g.dims[2] - 1) * g.spacing[2]};
}

// A blob centred in the middle 40% of the grid, of width in [min_width, min_width + 6).
BlobField RandomBlob(uint64_t seed, const GridGeometry& g, double min_width) {
  std::mt19937_64 rng(seed);
  const Vec3 hi = GridMax(g);
  std::uniform_real_distribution<double> u(0.3, 0.7);
  return BlobField{
      {g.origin[0] + u(rng) * (hi[0] - g.origin[0]), g.origin[1] + u(rng) * (hi[1] - g.origin[1]),
       g.origin[2] + u(rng) * (hi[2] - g.origin[2])},
      min_width + 6.0 * u(rng)};
}

Mesh CubeMeshInside(const GridGeometry& g, double margin) {
  Mesh m = testing::ReadMeditForTest(std::string(TETREFINE_SHARED_DATA_DIR) +
                                     "/unit_cube_1782tets.mesh");
  const Vec3 hi = GridMax(g);
  for (auto& p : m.points) {
    for (int a = 0; a < 3; ++a) {
      const double lo = g.origin[a] + margin, span = hi[a] - margin - lo;
      p[a] = lo + (p[a] + 0.5) * span;
    }
  }
  for (auto& t : m.tets) {
    if (SignedVolume6(m.points[t[0]], m.points[t[1]], m.points[t[2]], m.points[t[3]]) < 0) {
      std::swap(t[2], t[3]);
    }
  }
  return m;
}

class RefineEveryScheme : public ::testing::TestWithParam<RefineScheme> {};

void ExpectConformalEveryIteration(const Volume& volume, const Mesh& mesh, double epsilon,
                                   int max_iterations, RefineScheme scheme, RefineResult* out) {
  RefineOptions o;
  o.scheme = scheme;
  o.epsilon = epsilon;
  o.max_iterations = max_iterations;
  int checked = 0;
  o.on_iteration = [&](const IterationStats& s, const Mesh& m) {
    EXPECT_EQ(testing::ConformityProblem(mesh, m), "") << "iteration " << s.iteration;
    EXPECT_EQ(s.final_tets, static_cast<int64_t>(m.tets.size()));
    ++checked;
  };
  auto r = Refine(volume, mesh, o);
  ASSERT_TRUE(r.ok()) << r.status();
  EXPECT_EQ(checked, static_cast<int>(r->iterations.size()));
  *out = *std::move(r);
}

TEST_P(RefineEveryScheme, StructuredMeshStaysConformalAndConverges) {
  for (uint64_t seed : testing::Seeds(4)) {
    SCOPED_TRACE(::testing::Message() << "seed " << seed);
    std::printf("StructuredMesh seed %llu\n", static_cast<unsigned long long>(seed));
    const GridGeometry g = HeartGrid();
    const Vec3 hi = GridMax(g);
    const Volume volume = testing::AnalyticVolume(g, RandomBlob(seed, g, 14.0));
    const Mesh mesh = testing::FiveTetMesh(g.origin, hi, {6, 6, 3});
    for (double epsilon : {0.1, 0.05}) {
      RefineResult r;
      ExpectConformalEveryIteration(volume, mesh, epsilon, 30, GetParam(), &r);
      EXPECT_EQ(r.stop_reason, StopReason::kConverged) << "epsilon " << epsilon;
      EXPECT_LE(r.final_max_error, epsilon);
      ASSERT_FALSE(r.iterations.empty());
      EXPECT_GT(r.iterations[0].max_error, epsilon);
      // INT/FNT chain and the configuration histogram add up.
      int64_t tets = static_cast<int64_t>(mesh.tets.size());
      for (const auto& s : r.iterations) {
        EXPECT_EQ(s.initial_tets, tets);
        tets = s.final_tets;
        int64_t histogram = 0, produced = 0;
        for (int c = 0; c < kNumConfigurations; ++c) {
          histogram += s.configurations[c];
          produced +=
              s.configurations[c] * ConfigurationTetCount(static_cast<Configuration>(c), false);
        }
        EXPECT_EQ(histogram, s.initial_tets);
        EXPECT_EQ(s.tets_with_error, s.initial_tets - s.configurations[0]);
        // A better tiling than the table's has as many children or one fewer (3c, 4a); the
        // paper's scheme only cuts by the table.
        const int64_t table_tets = produced + 5 * s.schonhardt_prisms;
        EXPECT_LE(s.final_tets, table_tets);
        EXPECT_GE(s.final_tets, table_tets - s.other_tilings);
        if (GetParam() == RefineScheme::kPaper) {
          EXPECT_EQ(s.other_tilings, 0);
        }
      }
      EXPECT_EQ(r.tet_iteration.size(), r.mesh.tets.size());
      EXPECT_EQ(r.tet_quality.size(), r.mesh.tets.size());
      EXPECT_GT(r.final_quality.min, 0.0);
      // The lattice inside the tets agrees far better than the coarse mesh did.
      EXPECT_EQ(r.lattice.points_sampled, 165 * r.lattice.tets_sampled);
      EXPECT_LT(r.lattice.max_error, r.iterations[0].max_error);
    }
  }
}

// Edge errors evaluated from scratch (eq. 3) over a mesh's unique edges.
struct FreshErrors {
  double max = 0.0, mean = 0.0;
  int64_t split = 0;
};
FreshErrors EvaluateFromScratch(const Volume& v, const Mesh& m, double norm, double epsilon,
                                double min_length) {
  const auto edges = testing::UniqueEdges(m.tets);
  FreshErrors f;
  for (const auto& [a, b] : edges) {
    const Vec3 &p = m.points[a], &q = m.points[b];
    const Vec3 mid = {0.5 * (p[0] + q[0]), 0.5 * (p[1] + q[1]), 0.5 * (p[2] + q[2])};
    const double error = std::abs(v.Sample(mid) - 0.5 * (m.values[a] + m.values[b])) / norm;
    const double l2 = (p[0] - q[0]) * (p[0] - q[0]) + (p[1] - q[1]) * (p[1] - q[1]) +
                      (p[2] - q[2]) * (p[2] - q[2]);
    f.max = std::max(f.max, error);
    f.mean += error;
    f.split += error > epsilon && l2 >= min_length * min_length;
  }
  f.mean /= static_cast<double>(edges.size());
  return f;
}

// Each iteration reuses the midpoint values of the edges it did not split; its statistics and
// the final errors must be exactly what a fresh evaluation of the mesh gives.
TEST_P(RefineEveryScheme, EdgeErrorsOfEveryIterationMatchAFreshEvaluation) {
  for (uint64_t seed : testing::Seeds(3)) {
    SCOPED_TRACE(::testing::Message() << "seed " << seed);
    std::printf("FreshEvaluation seed %llu\n", static_cast<unsigned long long>(seed));
    const GridGeometry g = HeartGrid();
    const Vec3 hi = GridMax(g);
    const Volume volume = testing::AnalyticVolume(g, RandomBlob(seed, g, 6.0));
    RefineOptions o;
    o.scheme = GetParam();
    o.scheme = GetParam();
    o.epsilon = 0.02;
    o.max_iterations = 4;
    o.lattice_n = 0;
    o.min_edge_length = 0.5;
    std::vector<Mesh> meshes;
    o.on_iteration = [&](const IterationStats&, const Mesh& m) { meshes.push_back(m); };
    auto r = Refine(volume, testing::FiveTetMesh(g.origin, hi, {6, 6, 3}), o);
    ASSERT_TRUE(r.ok()) << r.status();
    ASSERT_EQ(meshes.size(), r->iterations.size());
    ASSERT_GE(meshes.size(), 2u);
    // lattice_n = 0: no check ran, and the result says so rather than "order 8, max 0".
    EXPECT_EQ(r->lattice.n, 0);
    EXPECT_EQ(r->lattice.tets_sampled, 0);
    for (size_t i = 0; i < meshes.size(); ++i) {
      const FreshErrors f =
          EvaluateFromScratch(volume, meshes[i], r->norm_coeff, o.epsilon, *o.min_edge_length);
      const bool last = i + 1 == meshes.size();
      const double max = last ? r->final_max_error : r->iterations[i + 1].max_error;
      const double mean = last ? r->final_mean_error : r->iterations[i + 1].mean_error;
      EXPECT_EQ(max, f.max) << "after iteration " << i + 1;
      EXPECT_NEAR(mean, f.mean, 1e-12 * f.mean) << "after iteration " << i + 1;
      if (!last) {
        const IterationStats& next = r->iterations[i + 1];
        EXPECT_EQ(next.split_edges - next.closure_edges - next.guard_edges, f.split)
            << "iteration " << i + 2;
      }
    }
  }
}

// A feature far sharper than the mesh: the paper's scheme flattens tets step by step near it
// (found by this test: without the quality floor, tets inverted by rounding at iteration 29).
// However long it runs, every tet stays positive and the mesh conformal; it stops at the floor.
TEST(Refine, SharpFeatureStopsThePaperSchemeAtTheQualityFloor) {
  const GridGeometry g = HeartGrid();
  const Volume volume = testing::AnalyticVolume(g, BlobField{{20.3, 37.1, 31.7}, 4.0});
  const Mesh mesh = testing::FiveTetMesh(g.origin, GridMax(g), {6, 6, 3});
  RefineResult r;
  ExpectConformalEveryIteration(volume, mesh, 0.05, 60, RefineScheme::kPaper, &r);
  EXPECT_EQ(r.stop_reason, StopReason::kQualityFloor);
  EXPECT_LT(r.next_iteration_min_quality, 1e-6);
  EXPECT_GE(r.final_quality.min, 1e-6);
  EXPECT_GT(r.iterations.size(), 5u);
}

// The same feature under the default scheme: it reaches epsilon at every edge midpoint within
// 32 iterations with no tet flattened (measured: min quality 0.40x, mean 0.9x of the input's;
// the paper's scheme ends at 1e-6).
TEST(Refine, SharpFeatureConvergesUnderTheLongestEdgeScheme) {
  const GridGeometry g = HeartGrid();
  const Volume volume = testing::AnalyticVolume(g, BlobField{{20.3, 37.1, 31.7}, 4.0});
  const Mesh mesh = testing::FiveTetMesh(g.origin, GridMax(g), {6, 6, 3});
  RefineResult r;
  ExpectConformalEveryIteration(volume, mesh, 0.05, 32, RefineScheme::kLongestEdge, &r);
  EXPECT_EQ(r.stop_reason, StopReason::kConverged);
  EXPECT_LE(r.final_max_error, 0.05);
  EXPECT_GE(r.final_quality.min, 0.3 * r.initial_quality.min);
  EXPECT_GE(r.final_quality.mean, 0.8 * r.initial_quality.mean);
}

// Edges kept whole by min_edge_length: once only they fail, the run stops with kMinEdgeLength
// (a sweep found such runs reported as converged with the largest midpoint error far above
// epsilon), and certified mode certifies nothing.
TEST(Refine, OnlyShortEdgesLeftStopsWithMinEdgeLength) {
  const GridGeometry g = HeartGrid();
  const Volume volume = testing::AnalyticVolume(g, BlobField{{20.3, 37.1, 31.7}, 4.0});
  const Mesh mesh = testing::FiveTetMesh(g.origin, GridMax(g), {6, 6, 3});
  for (const bool certify : {false, true}) {
    SCOPED_TRACE(certify ? "certify" : "longest-edge");
    RefineOptions o;
    o.epsilon = 0.05;
    o.max_iterations = 32;
    o.certify = certify;
    o.min_edge_length = 2.0 * g.spacing[0];
    absl::StatusOr<RefineResult> r = Refine(volume, mesh, o);
    ASSERT_TRUE(r.ok()) << r.status();
    EXPECT_EQ(r->stop_reason, StopReason::kMinEdgeLength);
    EXPECT_EQ(StopReasonName(r->stop_reason), "min_edge_length");
    EXPECT_LT(r->certified_max_error, 0.0);
    ASSERT_FALSE(r->iterations.empty());
    EXPECT_GT(r->iterations.back().short_edges_kept, 0);
    // Certified mode judges an edge by its maximum along it, which can exceed epsilon where
    // its midpoint does not.
    if (!certify) {
      EXPECT_GT(r->final_max_error, o.epsilon);
    }
    // A bound above every edge: nothing is split, in certified mode too (its tet test split
    // the longest edge of failing tets whatever its length, found by a sweep).
    o.min_edge_length = 1e3;
    r = Refine(volume, mesh, o);
    ASSERT_TRUE(r.ok()) << r.status();
    EXPECT_EQ(r->stop_reason, StopReason::kMinEdgeLength);
    EXPECT_TRUE(r->iterations.empty());
    EXPECT_EQ(r->mesh.tets.size(), mesh.tets.size());
    // Without the bound the same run converges.
    o.min_edge_length = 0.0;
    r = Refine(volume, mesh, o);
    ASSERT_TRUE(r.ok()) << r.status();
    EXPECT_EQ(r->stop_reason, StopReason::kConverged);
  }
}

TEST_P(RefineEveryScheme, UnstructuredCubeMeshStaysConformal) {
  for (uint64_t seed : testing::Seeds(3)) {
    SCOPED_TRACE(::testing::Message() << "seed " << seed);
    std::printf("UnstructuredCube seed %llu\n", static_cast<unsigned long long>(seed));
    std::mt19937_64 rng(seed);
    const GridGeometry g = HeartGrid();
    const Vec3 hi = GridMax(g);
    std::uniform_real_distribution<double> u(0.3, 0.7);
    const BlobField field{
        {g.origin[0] + u(rng) * (hi[0] - g.origin[0]), g.origin[1] + u(rng) * (hi[1] - g.origin[1]),
         g.origin[2] + u(rng) * (hi[2] - g.origin[2])},
        5.0};
    const Volume volume = testing::AnalyticVolume(g, field);
    const Mesh mesh = CubeMeshInside(g, 1.0 + u(rng));
    ASSERT_EQ(mesh.tets.size(), 1782u);
    RefineResult r;
    ExpectConformalEveryIteration(volume, mesh, 0.05, 4, GetParam(), &r);
    EXPECT_GE(r.iterations.size(), 2u);
  }
}

Mesh Renumbered(const Mesh& m, std::mt19937_64& rng) {
  std::vector<uint32_t> perm(m.points.size());
  std::iota(perm.begin(), perm.end(), 0u);
  std::shuffle(perm.begin(), perm.end(), rng);
  Mesh out;
  out.points.resize(m.points.size());
  for (size_t i = 0; i < perm.size(); ++i) out.points[perm[i]] = m.points[i];
  for (Tet t : m.tets) {
    for (auto& i : t) i = perm[i];
    // An even permutation of the corners keeps the orientation.
    std::rotate(t.begin(), t.begin() + 1, t.begin() + 3);
    out.tets.push_back(t);
  }
  std::shuffle(out.tets.begin(), out.tets.end(), rng);
  return out;
}

TEST_P(RefineEveryScheme, SameGeometryWhateverTheVertexNumbering) {
  // The structured mesh has many exactly equal diagonals, so the tie-break is exercised.
  const GridGeometry g = HeartGrid();
  const Volume volume = testing::AnalyticVolume(g, BlobField{{20, 40, 30}, 9.0});
  const Mesh mesh = testing::FiveTetMesh(g.origin, GridMax(g), {5, 5, 3});
  RefineOptions o;
  o.scheme = GetParam();
  o.epsilon = 0.05;
  o.max_iterations = 3;
  auto base = Refine(volume, mesh, o);
  ASSERT_TRUE(base.ok());
  for (uint64_t seed : testing::Seeds(3)) {
    std::printf("Renumbering seed %llu\n", static_cast<unsigned long long>(seed));
    std::mt19937_64 rng(seed);
    auto other = Refine(volume, Renumbered(mesh, rng), o);
    ASSERT_TRUE(other.ok());
    EXPECT_EQ(testing::GeometricTets(base->mesh), testing::GeometricTets(other->mesh))
        << "seed " << seed;
    auto sorted_points = [](std::vector<Vec3> p) {
      std::sort(p.begin(), p.end());
      return p;
    };
    EXPECT_EQ(sorted_points(base->mesh.points), sorted_points(other->mesh.points));
  }
}

TEST_P(RefineEveryScheme, SameBitsWhateverTheThreadCount) {
  const GridGeometry g = HeartGrid();
  const Volume volume = testing::AnalyticVolume(g, BlobField{{5, 30, 20}, 7.0});
  const Mesh mesh = testing::FiveTetMesh(g.origin, GridMax(g), {10, 10, 5});
  RefineOptions o;
  o.scheme = GetParam();
  o.epsilon = 0.02;
  o.max_iterations = 4;
  o.threads = 1;
  auto one = Refine(volume, mesh, o);
  o.threads = 2;
  auto two = Refine(volume, mesh, o);
  ASSERT_TRUE(one.ok() && two.ok());
  EXPECT_EQ(one->mesh.points, two->mesh.points);
  EXPECT_EQ(one->mesh.values, two->mesh.values);
  EXPECT_EQ(one->mesh.tets, two->mesh.tets);
  EXPECT_EQ(one->tet_quality, two->tet_quality);
  ASSERT_EQ(one->iterations.size(), two->iterations.size());
  for (size_t i = 0; i < one->iterations.size(); ++i) {
    EXPECT_EQ(one->iterations[i].mean_error, two->iterations[i].mean_error);
    EXPECT_EQ(one->iterations[i].quality.mean, two->iterations[i].quality.mean);
  }
  EXPECT_EQ(one->lattice.mean_error, two->lattice.mean_error);
}

TEST_P(RefineEveryScheme, SlabGivesTheSameBitsAsTheWholeVolume) {
  const GridGeometry g = HeartGrid();
  const Volume whole = testing::AnalyticVolume(g, BlobField{{15, 30, 25}, 9.0});
  // A mesh over part of the grid and the slab of samples that covers it.
  const Vec3 lo = {g.origin[0] + 3 * g.spacing[0], g.origin[1] + 2 * g.spacing[1],
                   g.origin[2] + 1 * g.spacing[2]};
  const Vec3 hi = {g.origin[0] + 15 * g.spacing[0], g.origin[1] + 14 * g.spacing[1],
                   g.origin[2] + 7 * g.spacing[2]};
  const Mesh mesh = testing::FiveTetMesh(lo, hi, {4, 4, 3});
  // One voxel of margin around the mesh's box, as a sharding client sends it.
  const Index3 slo = {2, 1, 0}, shi = {17, 16, 9};
  std::vector<std::byte> bytes;
  for (int64_t k = slo[2]; k < shi[2]; ++k)
    for (int64_t j = slo[1]; j < shi[1]; ++j)
      for (int64_t i = slo[0]; i < shi[0]; ++i) {
        const double v = whole.At(i, j, k);
        const auto* b = reinterpret_cast<const std::byte*>(&v);
        bytes.insert(bytes.end(), b, b + sizeof v);
      }
  auto slab = Volume::Create(g, slo, shi, VoxelType::kFloat64, bytes);
  ASSERT_TRUE(slab.ok()) << slab.status();
  RefineOptions o;
  o.scheme = GetParam();
  o.epsilon = 0.03;
  o.max_iterations = 4;
  const auto range = whole.ValueRange();
  o.norm_coeff = range[1] - range[0];
  auto a = Refine(whole, mesh, o);
  auto b = Refine(*slab, mesh, o);
  ASSERT_TRUE(a.ok() && b.ok()) << b.status();
  EXPECT_GT(a->iterations.size(), 1u);
  EXPECT_EQ(a->mesh.points, b->mesh.points);
  EXPECT_EQ(a->mesh.values, b->mesh.values);
  EXPECT_EQ(a->mesh.tets, b->mesh.tets);
  // A slab that does not hold the mesh is refused, naming the vertex.
  auto tight = Volume::Create(g, {4, 2, 1}, {16, 15, 8}, VoxelType::kFloat64,
                              std::vector<std::byte>(12 * 13 * 7 * sizeof(double)));
  ASSERT_TRUE(tight.ok());
  auto refused = Refine(*tight, mesh, o);
  ASSERT_FALSE(refused.ok());
  EXPECT_NE(refused.status().message().find("mesh.points[0]"), std::string::npos)
      << refused.status();
}

// A non-finite voxel is named by its grid index, as a viewer shows it: a slab's voxel
// (5, 6, 7) of the whole grid, not its place in the slab's data (the message said "voxel 2105
// of the slab" until a CLI sweep found it).
TEST(VolumeCreate, NonFiniteVoxelIsNamedByItsGridIndex) {
  GridGeometry g;
  g.dims = {10, 10, 10};
  const Index3 lo = {2, 3, 4}, hi = {8, 9, 10};
  std::vector<double> values(6 * 6 * 6, 1.0);
  values[(5 - 2) + 6 * ((6 - 3) + 6 * (7 - 4))] = std::numeric_limits<double>::quiet_NaN();
  std::vector<std::byte> bytes(values.size() * sizeof(double));
  std::memcpy(bytes.data(), values.data(), bytes.size());
  auto volume = Volume::Create(g, lo, hi, VoxelType::kFloat64, bytes);
  ASSERT_FALSE(volume.ok());
  EXPECT_EQ(volume.status().message(), "volume voxel (5, 6, 7) is not finite (nan)");
}

// Values near the largest double overflowed the interpolation and the value range: every error
// was inf (refinement ran to its budget) or, for +-1.7e308, the range was inf and every error 0
// ("converged" at once). Volumes beyond +-kMaxVoxelMagnitude are refused, naming the voxel; the
// bound itself, and a refinement of values just under it scaled from a small field, work.
TEST(VolumeCreate, ValuesBeyondTheMagnitudeBoundAreRefused) {
  GridGeometry g;
  g.dims = {4, 4, 4};
  for (const double big : {1.7e308, -1.7e308, 1e301, -2e300}) {
    std::vector<double> values(64, 1.0);
    values[1 + 4 * (2 + 4 * 3)] = big;
    auto volume = Volume::FromDoubles(g, values);
    ASSERT_FALSE(volume.ok()) << big;
    EXPECT_EQ(volume.status().message(),
              absl::StrCat("volume voxel (1, 2, 3) is ", big,
                           ": beyond +-1e+300 the interpolation and the value range overflow; "
                           "rescale the volume"));
  }
  // At the bound the arithmetic stays finite: the same field at 1 and at 1e300 refines alike.
  const GridGeometry heart = HeartGrid();
  const Volume unit = testing::AnalyticVolume(heart, BlobField{{20, 40, 30}, 6.0});
  ASSERT_EQ(unit.type(), VoxelType::kFloat64);
  std::vector<double> scaled(static_cast<size_t>(unit.voxel_count()));
  std::memcpy(scaled.data(), unit.data().data(), scaled.size() * sizeof(double));
  double largest = 0.0;
  for (double x : scaled) largest = std::max(largest, std::abs(x));
  for (double& x : scaled) x *= kMaxVoxelMagnitude / largest;
  auto huge = Volume::FromDoubles(heart, scaled);
  ASSERT_TRUE(huge.ok()) << huge.status();
  const Mesh mesh = testing::FiveTetMesh(heart.origin, GridMax(heart), {2, 2, 2});
  RefineOptions o;
  o.epsilon = 0.05;
  absl::StatusOr<RefineResult> a = Refine(unit, mesh, o), b = Refine(*huge, mesh, o);
  ASSERT_TRUE(a.ok() && b.ok());
  EXPECT_EQ(b->stop_reason, StopReason::kConverged);
  EXPECT_EQ(b->mesh.tets.size(), a->mesh.tets.size());
  ASSERT_FALSE(b->iterations.empty());
  EXPECT_TRUE(std::isfinite(b->iterations[0].max_error));
  EXPECT_NEAR(b->iterations[0].max_error, a->iterations[0].max_error, 1e-9);
}

// An input whose own worst tet is below min_quality (1e-6): its children are about as flat,
// and the fixed floor stopped every scheme before its first iteration with nothing refined (an
// outside review: a TetGen mesh of a jittered grid, "Stopped after 0 iterations:
// quality_floor"). The floor is half the input's worst for such inputs (QualityFloor).
TEST_P(RefineEveryScheme, AnInputSliverBelowTheFloorIsRefinedNotRefused) {
  const GridGeometry g = HeartGrid();
  const Volume volume = testing::AnalyticVolume(g, BlobField{{20.3, 37.1, 31.7}, 12.0});
  Mesh mesh;
  // A cap: the fourth corner 5e-9 mm above the interior of a 40 mm triangle.
  mesh.points = {{0, 10, 20}, {40, 10, 20}, {0, 50, 20}, {13, 23, 20 + 5e-9}};
  mesh.tets = {{0, 1, 2, 3}};
  const double input_worst =
      MeanRatio(mesh.points[0], mesh.points[1], mesh.points[2], mesh.points[3]);
  ASSERT_LT(input_worst, 0.5e-6);
  const double input_volume6 =
      SignedVolume6(mesh.points[0], mesh.points[1], mesh.points[2], mesh.points[3]);
  for (const bool certify : {false, true}) {
    SCOPED_TRACE(::testing::Message() << "certify " << certify);
    RefineOptions o;
    o.scheme = GetParam();
    o.certify = certify;
    o.epsilon = 0.05;
    o.max_iterations = 4;
    o.on_iteration = [&](const IterationStats& s, const Mesh& m) {
      // Conformal and positive (testing::ConformityProblem also compares volumes to 1e-9 of
      // the total, which a sliver's own rounding exceeds: its volume is 1e-12 of its edges'
      // cube, so the midpoints' rounding moves it by about 1e-6 of itself).
      EXPECT_TRUE(CheckConformity(m.points, m.tets).ok()) << "iteration " << s.iteration;
      double volume6 = 0.0;
      for (const Tet& t : m.tets) {
        const double v6 =
            SignedVolume6(m.points[t[0]], m.points[t[1]], m.points[t[2]], m.points[t[3]]);
        EXPECT_GT(v6, 0.0) << "iteration " << s.iteration;
        volume6 += v6;
      }
      EXPECT_NEAR(volume6, input_volume6, 1e-4 * input_volume6) << "iteration " << s.iteration;
      // Held to half the input's worst, not to 1e-6.
      EXPECT_GE(s.quality.min, static_cast<float>(0.5 * input_worst) * (1 - 1e-6));
    };
    auto r = Refine(volume, mesh, o);
    ASSERT_TRUE(r.ok()) << r.status();
    ASSERT_FALSE(r->iterations.empty()) << StopReasonName(r->stop_reason);
    // What the fixed floor refused: the first iteration's children are below 1e-6.
    EXPECT_LT(r->iterations[0].quality.min, 1e-6);
    EXPECT_GT(r->mesh.tets.size(), 1u);
  }
  EXPECT_EQ(QualityFloor(std::nullopt, 1e-7), 0.5e-7);
  EXPECT_EQ(QualityFloor(std::nullopt, 0.4), kDefaultMinQuality);
  // A floor the caller sets is theirs.
  EXPECT_EQ(QualityFloor(0.3, 0.4), 0.3);
  EXPECT_EQ(QualityFloor(1e-6, 1e-7), 1e-6);
  EXPECT_EQ(QualityFloor(0.0, 1e-7), 0.0);
}

TEST_P(RefineEveryScheme, StopsBeforeExceedingTheTetBudget) {
  const GridGeometry g = HeartGrid();
  const Volume volume = testing::AnalyticVolume(g, BlobField{{20, 40, 30}, 6.0});
  const Mesh mesh = testing::FiveTetMesh(g.origin, GridMax(g), {4, 4, 2});
  RefineOptions o;
  o.scheme = GetParam();
  o.epsilon = 0.01;
  o.max_tets = 400;
  auto r = Refine(volume, mesh, o);
  ASSERT_TRUE(r.ok());
  EXPECT_EQ(r->stop_reason, StopReason::kTetBudget);
  EXPECT_GT(r->next_iteration_tets, 400);
  EXPECT_LE(static_cast<int64_t>(r->mesh.tets.size()), 400);
  EXPECT_EQ(testing::ConformityProblem(mesh, r->mesh), "");
}

TEST_P(RefineEveryScheme, CancellationInsideAnIterationKeepsTheLastCompleteMesh) {
  const GridGeometry g = HeartGrid();
  const Volume volume = testing::AnalyticVolume(g, BlobField{{20, 40, 30}, 6.0});
  const Mesh mesh = testing::FiveTetMesh(g.origin, GridMax(g), {12, 12, 6});
  RefineOptions o;
  o.scheme = GetParam();
  o.epsilon = 0.001;
  std::atomic<int> polls{0};
  std::atomic<int> completed{0};
  o.on_iteration = [&](const IterationStats&, const Mesh&) { ++completed; };
  // Cancel on the third poll: inside the first iteration, which polls once per block.
  o.should_cancel = [&] { return ++polls > 2; };
  auto r = Refine(volume, mesh, o);
  ASSERT_TRUE(r.ok());
  EXPECT_EQ(r->stop_reason, StopReason::kCancelled);
  EXPECT_EQ(completed.load(), 0);
  EXPECT_EQ(r->mesh.tets, mesh.tets);
}

INSTANTIATE_TEST_SUITE_P(Schemes, RefineEveryScheme,
                         ::testing::Values(RefineScheme::kPaper, RefineScheme::kLongestEdge),
                         [](const ::testing::TestParamInfo<RefineScheme>& info) {
                           return info.param == RefineScheme::kPaper ? "Paper" : "LongestEdge";
                         });

}  // namespace
}  // namespace tetrefine
