// tetrefine mesh: an initial mesh immersed in a volume, five tets per (block of) voxel cells.

#include <cstdio>
#include <limits>
#include <optional>
#include <utility>

#include "absl/strings/str_cat.h"
#include "client/cli/command_support.h"
#include "client/cli/commands.h"
#include "client/cli/exit_codes.h"
#include "client/cli/file_kind.h"
#include "client/cli/grid_mesher.h"
#include "client/cli/mesh_report.h"
#include "client/cli/mesh_write_flags.h"
#include "client/io/mesh_io.h"

namespace tetrefine::cli {

const CommandSpec& MeshSpec() {
  static const CommandSpec* spec = [] {
    auto* s = new CommandSpec{
        .name = "mesh",
        .summary = "Make an initial tet mesh of a volume's voxel grid",
        .usage = "tetrefine mesh --volume V [--block B] [--mask-threshold T] --output OUT [flags]",
        .description =
            "Cuts the volume's grid into cells of B x B x B voxels (the last cell along an axis\n"
            "takes what remains, so the mesh spans the whole volume) and each cell into 5 tets,\n"
            "alternating the split between neighbouring cells so shared faces match. Vertices sit\n"
            "on voxel samples (world RAS mm) and carry the sample as `value`; tets are positively\n"
            "oriented; only vertices some tet uses are written.\n"
            "With --mask-threshold T only cells whose 8 corner samples are all >= T are meshed:\n"
            "the paper's liver set-up, a tetrahedrization of the voxels inside the organ.",
        .flags =
            {
                {"volume", "FILE",
                 "volume: .nii .nii.gz .hdr .nrrd .nhdr .mha .mhd .vti .pvti .vtk, DICOM series "
                 "dir or file",
                 true},
                {"output", "FILE", "mesh to write: .vtu .vtk .msh .mesh .meshb .ele", true},
                {"block", "B", "voxels per cell edge (default 1)"},
                {"mask-threshold", "T", "mesh only cells whose 8 corner samples are all >= T"},
            },
        .positional = ""};
    for (FlagSpec& flag : MeshWriteFlagSpecs()) s->flags.push_back(std::move(flag));
    return s;
  }();
  return *spec;
}

int RunMesh(const std::vector<std::string>& args) {
  int exit_code = kExitOk;
  std::optional<ParsedArgs> parsed = ParseCommandLine(MeshSpec(), args, &exit_code);
  if (!parsed.has_value()) return exit_code;
  GridMeshOptions options;
  if (auto text = parsed->Get("block")) {
    absl::StatusOr<int64_t> block = ParseInteger("block", *text, 1, 1 << 20);
    if (!block.ok()) return Fail(block.status(), kExitUsage);
    options.block = *block;
  }
  if (auto text = parsed->Get("mask-threshold")) {
    absl::StatusOr<double> threshold = ParseFiniteDouble("mask-threshold", *text);
    if (!threshold.ok()) return Fail(threshold.status(), kExitUsage);
    options.mask_threshold = *threshold;
  }
  absl::StatusOr<io::MeshWriteOptions> write = MeshWriteOptionsFromArgs(*parsed);
  if (!write.ok()) return Fail(write.status(), kExitUsage);
  const std::string volume_path = *parsed->Get("volume");
  const std::string output = *parsed->Get("output");
  absl::Status output_ok = CheckOutputPath(output, "--output", /*mesh=*/true);
  // A legacy .vtk is a volume and a mesh format: the volume must not become its own mesh.
  if (output_ok.ok())
    output_ok = CheckNotTheSameFile({"--output", output}, {{"--volume", volume_path}});
  if (!output_ok.ok()) return Fail(output_ok, kExitUsage);

  absl::StatusOr<io::VolumeFile> volume = LoadVolume(volume_path, "--volume");
  if (!volume.ok()) return Fail(volume.status(), kExitUsage);
  PrintVolumeWarnings(*volume);
  absl::StatusOr<GridMesh> grid = MeshVolumeGrid(volume->volume, options);
  if (!grid.ok()) return Fail(absl::StrCat(volume_path, ": ", grid.status().message()), kExitUsage);
  const MeshReport report = AnalyzeMesh(grid->mesh);
  io::MeshFile file{.mesh = std::move(grid->mesh), .tet_iteration = {}, .tet_quality = {}};
  absl::Status written = io::WriteMesh(output, file, *write);
  if (!written.ok()) return Fail(written, kExitUsage);
  std::printf(
      "Wrote %s: %lld vertices, %lld tets from %lld of %lld cells (block %lld), volume %g "
      "mm^3, quality min %.6f mean %.6f\n",
      output.c_str(), static_cast<long long>(report.vertices), static_cast<long long>(report.tets),
      static_cast<long long>(grid->cells_kept), static_cast<long long>(grid->cells),
      static_cast<long long>(options.block), report.volume, report.quality_min,
      report.quality_mean);
  return kExitOk;
}

}  // namespace tetrefine::cli
