#include "tools/reproduce/cases.h"

#include <algorithm>
#include <filesystem>
#include <limits>
#include <optional>
#include <utility>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "bench/support/field_volume.h"
#include "client/io/mesh_io.h"
#include "client/io/read_volume.h"
#include "tools/reproduce/case_meshes.h"
#include "tools/reproduce/otsu_threshold.h"
#include "tools/reproduce/phantoms.h"

namespace tetrefine::reproduce {
namespace {

// Coarse initial meshes like the paper's (1,009, 988 and 10,955 tets).
constexpr int64_t kMaxCoarseTets = 10'000;
constexpr double kCubeMargin = 0.05;
constexpr double kHeartCellMm = 8.0;
constexpr int kMarschnerLobbBlock = 4;

std::string GridText(const Volume& v) {
  const GridGeometry& g = v.grid();
  return absl::StrFormat("%dx%dx%d voxels of %gx%gx%g mm", g.dims[0], g.dims[1], g.dims[2],
                         g.spacing[0], g.spacing[1], g.spacing[2]);
}

std::string Stem(const std::string& file) {
  std::string s = std::filesystem::path(file).filename().string();
  for (const char* ext : {".nii.gz", ".nii"}) {
    const std::string e = ext;
    if (s.size() > e.size() && s.compare(s.size() - e.size(), e.size(), e) == 0) {
      return s.substr(0, s.size() - e.size());
    }
  }
  return s;
}

void AddCubeCase(const std::string& name, const std::string& volume_name,
                 const std::shared_ptr<const Volume>& volume, const Mesh* cube, Inputs& in) {
  if (cube == nullptr) return;
  CaseInput c{.name = name + "_cube",
              .volume_name = volume_name,
              .mesh_kind = "unstructured cube",
              .description = absl::StrCat(
                  "The unstructured Delaunay cube mesh (unit_cube_1782tets.mesh, ",
                  cube->tets.size(), " tets) scaled per axis onto the volume's box less a ",
                  kCubeMargin * 100, "% margin on every side: vertices off the grid."),
              .volume = volume,
              .mesh = FitMeshInBox(*cube, volume->grid(), kCubeMargin)};
  in.study.push_back({absl::StrCat(volume_name, ", cube"), "coarse", volume, c.mesh});
  in.cases.push_back(std::move(c));
}

void AddRealVolume(const std::string& path, const Mesh* cube, Inputs& in) {
  absl::StatusOr<io::VolumeFile> file = io::ReadVolume(path);
  if (!file.ok()) {
    in.notes.push_back(absl::StrCat("skipped ", path, ": ", file.status().message()));
    return;
  }
  for (const std::string& w : file->warnings) in.notes.push_back(absl::StrCat("reader: ", w));
  auto volume = std::make_shared<const Volume>(std::move(file->volume));
  const std::string stem = Stem(path);
  const double threshold = OtsuThreshold(*volume);
  const auto [lo, hi] = volume->ValueRange();
  BlockChoice blocks = CoarseBlockMesh(*volume, threshold, kMaxCoarseTets);
  const std::string mask = absl::StrFormat(
      "Mask: Otsu's threshold %.6g of the value range [%.6g, %.6g]; a cell is kept when all 8 of "
      "its corner samples exceed it.",
      threshold, lo, hi);
  CaseInput c{.name = stem + "_blocks",
              .volume_name = stem,
              .mesh_kind = "5-tet blocks",
              .description =
                  absl::StrCat("MRI volume ", std::filesystem::path(path).filename().string(), ", ",
                               GridText(*volume), ", ", std::string(VoxelTypeName(volume->type())),
                               ". Mesh: blocks of ", blocks.block,
                               "^3 voxels cut into 5 tets each (the "
                               "smallest block in {2, 3, 4, 5, 6, 8} giving at most ",
                               kMaxCoarseTets, " tets). ", mask),
              .volume = volume,
              .mesh = std::move(blocks.mesh)};
  in.study.push_back({absl::StrCat(stem, ", voxel 5-tet"), "voxel-aligned", volume,
                      MaskedBlockMesh(*volume, threshold, 1)});
  in.study.push_back({absl::StrCat(stem, ", blocks of ", blocks.block), "coarse", volume, c.mesh});
  in.cases.push_back(std::move(c));
  AddCubeCase(stem, stem, volume, cube, in);
}

void AddHeart(const std::string& name, const GridGeometry& grid, const Mesh& shell, Inputs& in) {
  auto volume = std::make_shared<const Volume>(
      bench::SampleField(grid, VoxelType::kFloat32, HeartPhantomValue));
  const std::string volume_name = name + " phantom";
  in.cases.push_back(
      {.name = name + "_shell",
       .volume_name = volume_name,
       .mesh_kind = "shell",
       .description = absl::StrCat(
           "Left-ventricle perfusion phantom (tools/reproduce/phantoms.h) sampled on the paper's ",
           name, " grid: ", GridText(*volume), ", float32. Mesh: world cells of ", kHeartCellMm,
           " mm, 5 tets each, kept when the cell centre lies in the wall below the base plane "
           "(the same mesh on both heart grids)."),
       .volume = volume,
       .mesh = shell});
  const double threshold = OtsuThreshold(*volume);
  in.study.push_back({absl::StrCat(volume_name, ", voxel 5-tet"), "voxel-aligned", volume,
                      MaskedBlockMesh(*volume, threshold, 1)});
  in.study.push_back({absl::StrCat(volume_name, ", shell"), "coarse", volume, shell});
}

void AddMarschnerLobb(int n, int block, const Mesh* cube, Inputs& in) {
  auto volume = std::make_shared<const Volume>(
      bench::SampleField(MarschnerLobbGrid(n), VoxelType::kFloat64, MarschnerLobbValue));
  const std::string name = absl::StrCat("marschner_lobb_", n);
  const double none = -std::numeric_limits<double>::infinity();
  in.cases.push_back({.name = name + "_blocks",
                      .volume_name = name,
                      .mesh_kind = "5-tet blocks",
                      .description = absl::StrCat(
                          "Marschner-Lobb signal (f_M = 6, alpha = 0.25) on [-1, 1]^3 sampled on ",
                          GridText(*volume), ", float64. Mesh: blocks of ", block,
                          "^3 voxels cut into 5 tets each, whole box."),
                      .volume = volume,
                      .mesh = MaskedBlockMesh(*volume, none, block)});
  in.study.push_back({absl::StrCat(name, ", voxel 5-tet"), "voxel-aligned", volume,
                      MaskedBlockMesh(*volume, none, 1)});
  in.study.push_back(
      {absl::StrCat(name, ", blocks of ", block), "coarse", volume, in.cases.back().mesh});
  AddCubeCase(name, name, volume, cube, in);
}

// The box both heart grids cover: the intersection of their world bounds. Exact for the
// axis-aligned phantom grids; for an oblique grid the bounds enclose more than the grid samples,
// so a shell built there could leave it (the phantoms never are oblique).
std::pair<Vec3, Vec3> CommonBox(const GridGeometry& a, const GridGeometry& b) {
  auto bounds = [](const GridGeometry& g) {
    return WorldBounds(g, {0.0, 0.0, 0.0},
                       {static_cast<double>(g.dims[0] - 1), static_cast<double>(g.dims[1] - 1),
                        static_cast<double>(g.dims[2] - 1)});
  };
  const std::array<Vec3, 2> ba = bounds(a), bb = bounds(b);
  Vec3 lo, hi;
  for (int i = 0; i < 3; ++i) {
    lo[i] = std::max(ba[0][i], bb[0][i]);
    hi[i] = std::min(ba[1][i], bb[1][i]);
  }
  return {lo, hi};
}

}  // namespace

Inputs BuildInputs(const InputOptions& options) {
  Inputs in;
  const auto [lo, hi] = CommonBox(Heart1Grid(), Heart2Grid());
  const Mesh shell = HeartShellMesh(kHeartCellMm, lo, hi);
  if (options.quick) {
    AddHeart("heart2", Heart2Grid(), shell, in);
    AddMarschnerLobb(17, kMarschnerLobbBlock, nullptr, in);
    return in;
  }
  std::optional<Mesh> cube;
  const std::string cube_path = options.data_dir + "/unit_cube_1782tets.mesh";
  if (absl::StatusOr<io::MeshFile> f = io::ReadMesh(cube_path); f.ok()) {
    cube = std::move(f->mesh);
  } else {
    in.notes.push_back(absl::StrCat("skipped the cube mesh cases: ", f.status().message()));
  }
  const Mesh* cube_mesh = cube ? &*cube : nullptr;
  for (const char* file :
       {"epi_brain_58x58x24.nii.gz", "anatomical_33x41x25.nii", "t1_brain_128x128x62.nii.gz"}) {
    AddRealVolume(options.data_dir + "/" + file, cube_mesh, in);
  }
  AddHeart("heart1", Heart1Grid(), shell, in);
  AddHeart("heart2", Heart2Grid(), shell, in);
  AddMarschnerLobb(41, kMarschnerLobbBlock, cube_mesh, in);
  return in;
}

}  // namespace tetrefine::reproduce
