// The paper's method on the real volumes in ../shared/data: coarse structured meshes (5 tets per
// block of cells) and the unstructured cube mesh placed inside each volume, at epsilon 0.1 and
// 0.05. Every iteration must stay conformal and the discrepancy inside the tets (165-point
// lattice) must fall: its mean and the share of lattice points above epsilon.
//
// What this test found, and why it does not ask for the midpoint maximum to drop below epsilon:
// on these MRI volumes (skull and ventricle boundaries a voxel wide, noise) the paper's scheme
// does not converge. The edges still above epsilon after many iterations are all 1.5 to 5 voxels
// long: splitting only the marked edges joins each new midpoint to the far corners with edges as
// long as before, so near a sharp boundary about the same number of long edges is marked every
// iteration (anatomical, cube mesh, eps 0.1: ~55 per iteration from iteration 6 on, midpoint max
// ~0.29 throughout, quality falling 2.5x per iteration). The paper's own Table 5 stops above
// epsilon too. Runs end on max_iterations, the tet budget or the quality floor.
#include <gtest/gtest.h>

#include <ostream>
#include <string>

#include "client/io/read_volume.h"
#include "core/refine.h"
#include "tests/support/geometry.h"
#include "tests/support/mesh_checks.h"

namespace tetrefine {
namespace {

std::string DataPath(const std::string& name) {
  return std::string(TETREFINE_SHARED_DATA_DIR) + "/" + name;
}

Vec3 GridMax(const GridGeometry& g) {
  return {g.origin[0] + (g.dims[0] - 1) * g.spacing[0],
          g.origin[1] + (g.dims[1] - 1) * g.spacing[1],
          g.origin[2] + (g.dims[2] - 1) * g.spacing[2]};
}

struct Case {
  const char* file;
  int block;  // cells per structured block, per axis
};

// In test names: GoogleTest would print the struct's bytes (a pointer among them, so the name
// changed from one build to the next), and ctest appends them.
void PrintTo(const Case& c, std::ostream* os) { *os << c.file << ", blocks of " << c.block; }

class RealData : public ::testing::TestWithParam<Case> {};

void RunAndCheck(const Volume& volume, const Mesh& mesh, double epsilon, const std::string& what) {
  RefineOptions o;
  o.epsilon = epsilon;
  o.lattice_max_tets = 0;  // every tet: sampling would make before/after noisy
  o.max_iterations = 0;
  auto before = Refine(volume, mesh, o);
  ASSERT_TRUE(before.ok()) << what << ": " << before.status();
  o.max_iterations = 6;
  o.max_tets = 300000;
  o.on_iteration = [&](const IterationStats& s, const Mesh& m) {
    EXPECT_EQ(testing::ConformityProblem(mesh, m), "") << what << " iteration " << s.iteration;
  };
  auto r = Refine(volume, mesh, o);
  ASSERT_TRUE(r.ok()) << what << ": " << r.status();
  ASSERT_FALSE(r->iterations.empty()) << what;
  std::printf(
      "%s: %zu -> %zu tets in %zu iterations (%s); midpoint max %.3f -> %.3f; lattice "
      "volume-weighted mean %.4f -> %.4f, volume above eps %.2f%% -> %.2f%%, max %.3f -> %.3f; "
      "quality min %.3g\n",
      what.c_str(), mesh.tets.size(), r->mesh.tets.size(), r->iterations.size(),
      std::string(StopReasonName(r->stop_reason)).c_str(), r->iterations[0].max_error,
      r->final_max_error, before->lattice.volume_mean_error, r->lattice.volume_mean_error,
      100 * before->lattice.volume_share_above_epsilon, 100 * r->lattice.volume_share_above_epsilon,
      before->lattice.max_error, r->lattice.max_error, r->final_quality.min);
  EXPECT_NE(r->stop_reason, StopReason::kCancelled) << what;
  EXPECT_LT(r->lattice.volume_mean_error, 0.8 * before->lattice.volume_mean_error) << what;
  EXPECT_LT(r->lattice.volume_share_above_epsilon, 0.6 * before->lattice.volume_share_above_epsilon)
      << what;
  EXPECT_GE(r->final_quality.min, o.min_quality) << what;
}

TEST_P(RealData, StructuredAndUnstructuredMeshesRefineConformally) {
  const Case c = GetParam();
  auto file = io::ReadVolume(DataPath(c.file));
  ASSERT_TRUE(file.ok()) << file.status();
  const Volume& volume = file->volume;
  const GridGeometry& g = volume.grid();
  const Vec3 hi = GridMax(g);
  const std::array<int, 3> blocks = {static_cast<int>((g.dims[0] - 1) / c.block),
                                     static_cast<int>((g.dims[1] - 1) / c.block),
                                     static_cast<int>((g.dims[2] - 1) / c.block)};
  const Vec3 block_hi = {g.origin[0] + blocks[0] * c.block * g.spacing[0],
                         g.origin[1] + blocks[1] * c.block * g.spacing[1],
                         g.origin[2] + blocks[2] * c.block * g.spacing[2]};
  // The meshes are laid out in the grid's axis-aligned frame and, for an oblique volume (the EPI
  // and T1 files), rotated into its world frame: p -> origin + direction * (p - origin).
  auto to_volume_frame = [&](Mesh& mesh) {
    if (volume.axis_aligned()) return;
    const Mat3& d = g.direction;
    for (Vec3& p : mesh.points) {
      const Vec3 r{p[0] - g.origin[0], p[1] - g.origin[1], p[2] - g.origin[2]};
      for (int row = 0; row < 3; ++row) {
        p[row] = g.origin[row] + d[3 * row] * r[0] + d[3 * row + 1] * r[1] + d[3 * row + 2] * r[2];
      }
    }
    if (Determinant(d) < 0.0) {
      for (Tet& t : mesh.tets) std::swap(t[2], t[3]);
    }
  };
  Mesh structured = testing::FiveTetMesh(g.origin, block_hi, blocks);
  to_volume_frame(structured);
  Mesh cube = testing::ReadMeditForTest(DataPath("unit_cube_1782tets.mesh"));
  for (auto& p : cube.points) {
    for (int a = 0; a < 3; ++a) {
      const double margin = 0.05 * (hi[a] - g.origin[a]);
      p[a] = g.origin[a] + margin + (p[a] + 0.5) * (hi[a] - g.origin[a] - 2 * margin);
    }
  }
  to_volume_frame(cube);
  for (auto& t : cube.tets) {
    if (SignedVolume6(cube.points[t[0]], cube.points[t[1]], cube.points[t[2]], cube.points[t[3]]) <
        0) {
      std::swap(t[2], t[3]);
    }
  }
  for (double epsilon : {0.1, 0.05}) {
    RunAndCheck(volume, structured, epsilon,
                std::string(c.file) + " structured eps " + std::to_string(epsilon));
    RunAndCheck(volume, cube, epsilon,
                std::string(c.file) + " cube eps " + std::to_string(epsilon));
  }
}

INSTANTIATE_TEST_SUITE_P(SharedData, RealData,
                         ::testing::Values(Case{"anatomical_33x41x25.nii", 4},
                                           Case{"epi_brain_58x58x24.nii.gz", 4},
                                           Case{"t1_brain_128x128x62.nii.gz", 8}));

}  // namespace
}  // namespace tetrefine
