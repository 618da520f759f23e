// The pieces of tools/reproduce whose mistakes would not show in the report: the uniform
// baseline (conformal, volume-preserving 1:8), the masked block mesh and the JSON quoting.
#include <array>
#include <cmath>
#include <cstdio>
#include <random>
#include <set>
#include <vector>

#include "bench/support/field_volume.h"
#include "bench/support/five_tet_lattice.h"
#include "core/mesh_validation.h"
#include "core/quality.h"
#include "gtest/gtest.h"
#include "tests/support/geometry.h"
#include "tools/reproduce/case_meshes.h"
#include "tools/reproduce/uniform_refine.h"

namespace tetrefine::reproduce {
namespace {

Volume LinearVolume() {
  GridGeometry g;
  g.dims = {9, 9, 9};
  return bench::SampleField(g, VoxelType::kFloat64,
                            [](const Vec3& p) { return p[0] + 2 * p[1] - p[2]; });
}

double TotalVolume(const Mesh& m) {
  double v = 0.0;
  for (const Tet& t : m.tets) {
    v += SignedVolume6(m.points[t[0]], m.points[t[1]], m.points[t[2]], m.points[t[3]]);
  }
  return v / 6.0;
}

TEST(UniformRefineTest, SplitsEveryTetIntoEightConformally) {
  const Volume volume = LinearVolume();
  bench::CellLattice lattice;
  lattice.cells = {3, 2, 2};
  lattice.size = {2.5, 3.0, 3.5};
  Mesh mesh = bench::FiveTetLatticeMesh(lattice);
  SampleValues(volume, mesh);
  const Mesh fine = UniformRefine(volume, mesh);
  ASSERT_EQ(fine.tets.size(), 8 * mesh.tets.size());
  const auto edges = testing::UniqueEdges(mesh.tets);
  // One new vertex per edge: shared midpoints.
  EXPECT_EQ(fine.points.size(), mesh.points.size() + edges.size());
  EXPECT_NEAR(TotalVolume(fine), TotalVolume(mesh), 1e-9 * TotalVolume(mesh));
  for (const Tet& t : fine.tets) {
    EXPECT_GT(
        SignedVolume6(fine.points[t[0]], fine.points[t[1]], fine.points[t[2]], fine.points[t[3]]),
        0.0);
  }
  EXPECT_TRUE(CheckFaces(fine.points, fine.tets).ok());
  // On a linear field every new vertex is the average of its edge's values.
  ASSERT_EQ(fine.values.size(), fine.points.size());
  for (size_t i = 0; i < fine.points.size(); ++i) {
    const Vec3& p = fine.points[i];
    EXPECT_NEAR(fine.values[i], p[0] + 2 * p[1] - p[2], 1e-9);
  }
}

TEST(UniformRefineTest, RandomTetsKeepTheirVolume) {
  const uint64_t seed = 20261122;
  std::printf("seed %llu\n", static_cast<unsigned long long>(seed));
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 8.0);
  const Volume volume = LinearVolume();
  for (int trial = 0; trial < 200; ++trial) {
    Mesh m;
    for (int c = 0; c < 4; ++c) m.points.push_back({u(rng), u(rng), u(rng)});
    m.tets.push_back({0, 1, 2, 3});
    if (MeanRatio(m.points[0], m.points[1], m.points[2], m.points[3]) < 0.05) continue;
    if (TotalVolume(m) < 0) std::swap(m.tets[0][2], m.tets[0][3]);
    SampleValues(volume, m);
    const Mesh fine = UniformRefine(volume, UniformRefine(volume, m));
    ASSERT_EQ(fine.tets.size(), 64u);
    EXPECT_NEAR(TotalVolume(fine), TotalVolume(m), 1e-9 * TotalVolume(m)) << "trial " << trial;
  }
}

TEST(MaskedBlockMeshTest, KeepsBlocksWhoseCornersAllExceedTheThreshold) {
  GridGeometry g;
  g.dims = {9, 9, 5};
  // Above 0 only for x < 4.5: blocks of 2 with corners at x = 0, 2, 4 qualify, x = 6 does not.
  const Volume volume = bench::SampleField(g, VoxelType::kInt16,
                                           [](const Vec3& p) { return p[0] < 4.5 ? 10.0 : -10.0; });
  const Mesh m = MaskedBlockMesh(volume, 0.0, 2);
  EXPECT_EQ(m.tets.size(), 5u * 2 * 4 * 2);  // 2 of 4 blocks in x, 4 in y, 2 in z
  for (const Vec3& p : m.points) EXPECT_LE(p[0], 4.0);
  EXPECT_TRUE(CheckFaces(m.points, m.tets).ok());
}

}  // namespace
}  // namespace tetrefine::reproduce
