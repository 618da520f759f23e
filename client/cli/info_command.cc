// tetrefine info: what a volume or mesh file holds, as tetrefine reads it.

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "absl/strings/match.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/strings/str_join.h"
#include "client/cli/command_support.h"
#include "client/cli/commands.h"
#include "client/cli/exit_codes.h"
#include "client/cli/file_kind.h"
#include "client/cli/mesh_placement.h"
#include "client/cli/mesh_report.h"
#include "client/io/axis_codes.h"
#include "client/io/dicom_series.h"
#include "client/io/mesh_io.h"
#include "client/io/vtk_legacy_format.h"
#include "core/mesh_validation.h"

namespace tetrefine::cli {
namespace {

using Rows = std::vector<std::pair<std::string, std::string>>;

void PrintRows(const Rows& rows) {
  size_t width = 0;
  for (const auto& [name, value] : rows) width = std::max(width, name.size());
  for (const auto& [name, value] : rows) {
    std::printf("%-*s  %s\n", static_cast<int>(width), name.c_str(), value.c_str());
  }
}

std::string Triple(const std::array<double, 3>& v) {
  // + 0.0 prints a negative zero (a flipped axis's origin) as 0.
  return absl::StrCat("(", v[0] + 0.0, ", ", v[1] + 0.0, ", ", v[2] + 0.0, ")");
}

int VolumeInfo(const std::string& path) {
  absl::StatusOr<io::VolumeFile> file = LoadVolume(path, "FILE");
  if (!file.ok()) return Fail(file.status(), kExitUsage);
  const Volume& v = file->volume;
  const GridGeometry& g = v.grid();
  const std::array<double, 2> range = v.ValueRange();
  Rows rows = {
      {"file", path},
      {"kind", "volume"},
      {"dims", absl::StrCat(g.dims[0], " x ", g.dims[1], " x ", g.dims[2], " (", v.voxel_count(),
                            " voxels)")},
      {"voxel type", std::string(VoxelTypeName(v.type()))},
      {"spacing", absl::StrCat(g.spacing[0], " x ", g.spacing[1], " x ", g.spacing[2], " mm")},
      {"origin", absl::StrCat(Triple(g.origin), " mm, world RAS")},
      {"world box", absl::StrCat(FormatBox(VolumeWorldBox(v)), " mm")},
      {"value range", absl::StrCat("[", range[0], ", ", range[1], "]")},
  };
  // A grid whose axes are only flipped or swapped is not oblique: say so. (A file's diagonal
  // flips are undone when it is read, so such a grid has a permutation left.)
  if (v.axis_aligned()) {
    rows.push_back({"direction", "identity (axis-aligned)"});
  } else {
    const char* kind = GridFillsItsWorldBox(v) ? "axes flipped or swapped, not oblique" : "oblique";
    for (int r = 0; r < 3; ++r) {
      const double* d = g.direction.data() + 3 * r;
      rows.push_back(
          {r == 0 ? "direction" : "",
           absl::StrFormat(
               "[%12.6g %12.6g %12.6g]%s", d[0] + 0.0, d[1] + 0.0, d[2] + 0.0,
               r == 0 ? absl::StrCat("  (columns: world axes of i, j, k; ", kind, ")") : "")});
    }
  }
  // The file's storage order as imaging tools name it (nibabel's aff2axcodes, Slicer's RAS/LPS):
  // what a user compares with their other tools, whatever order the grid was read into.
  Mat3 file_axes;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) file_axes[3 * r + c] = file->affine[r][c];
  }
  const io::AxisCodes codes = io::AxisCodesOf(file_axes);
  std::vector<std::string> words;
  for (char c : codes.codes) words.push_back(io::AxisCodeWord(c));
  rows.push_back(
      {"orientation", absl::StrCat(codes.exact ? "" : "oblique, closest to ", codes.codes,
                                   " (the file's i, j, k run ", codes.exact ? "" : "nearest ",
                                   "to ", absl::StrJoin(words, ", "), ")")});
  // The file's storage-order index to world, in RAS (an LPS file's NRRD or MetaImage matrix has
  // x and y negated). "+ 0.0" turns the -0 of a negated zero into 0 (a sweep saw "-0" entries).
  for (int r = 0; r < 4; ++r) {
    const auto& a = file->affine[r];
    rows.push_back({r == 0 ? "file affine (RAS)" : "",
                    absl::StrFormat("[%12.6g %12.6g %12.6g %12.6g]", a[0] + 0.0, a[1] + 0.0,
                                    a[2] + 0.0, a[3] + 0.0)});
  }
  if (file->warnings.empty()) rows.push_back({"warnings", "none"});
  for (size_t i = 0; i < file->warnings.size(); ++i) {
    rows.push_back({i == 0 ? "warnings" : "", file->warnings[i]});
  }
  PrintRows(rows);
  return kExitOk;
}

// "3: 11 (9673 tets), 12 (10834 tets), 13 (7238 tets)": the distinct labels with their tet
// counts, the first twelve in ascending order.
std::string RegionSummary(const std::vector<int32_t>& labels) {
  std::map<int32_t, int64_t> counts;
  for (int32_t label : labels) ++counts[label];
  std::vector<std::string> parts;
  for (const auto& [label, n] : counts) {
    if (parts.size() == 12) {
      parts.emplace_back("...");
      break;
    }
    parts.push_back(absl::StrCat(label, " (", n, n == 1 ? " tet)" : " tets)"));
  }
  return absl::StrCat(counts.size(), ": ", absl::StrJoin(parts, ", "));
}

int MeshInfo(const std::string& path) {
  absl::StatusOr<io::MeshFile> file = LoadMesh(path, "FILE");
  if (!file.ok()) return Fail(file.status(), kExitUsage);
  const MeshReport r = AnalyzeMesh(file->mesh);
  std::vector<std::string> arrays;
  if (!file->mesh.values.empty()) arrays.emplace_back("value (per vertex)");
  if (!file->tet_iteration.empty()) arrays.emplace_back("iteration (per tet)");
  if (!file->tet_quality.empty()) arrays.emplace_back("quality (per tet)");
  // The region labels refine carries (a user could not tell whether a file's labels had been
  // recognised: a file-format sweep saw "arrays none" on labelled .msh, .vtu and .mesh files).
  if (!file->mesh.labels.empty()) {
    arrays.push_back(absl::StrCat(io::LabelArrayName(*file), " (region label per tet)"));
  }
  std::string array_text;
  for (const std::string& a : arrays)
    absl::StrAppend(&array_text, array_text.empty() ? "" : ", ", a);
  Rows rows = {
      {"file", path},
      {"kind", "tetrahedral mesh"},
      {"vertices", absl::StrCat(r.vertices, r.unused_vertices > 0
                                                ? absl::StrCat(" (", r.unused_vertices, " unused)")
                                                : "")},
      {"tets", absl::StrCat(r.tets)},
      {"bounding box", FormatBox(r.bounding_box)},
  };
  // Beyond +-1e30 a tet's volume and quality overflow (a sweep saw "volume inf", "mean -nan"):
  // the figures are left out and the row says why, as refine and verify refuse such a mesh.
  if (const absl::Status coordinates = CheckCoordinates(file->mesh.points); !coordinates.ok()) {
    rows.push_back({"geometry", absl::StrCat("not measured: ", coordinates.message())});
  } else {
    rows.insert(
        rows.end(),
        {{"volume", absl::StrFormat("%.9g", r.volume)},
         {"boundary area", absl::StrFormat("%.9g (%d faces)", r.boundary_area, r.boundary_faces)},
         {"quality (mean ratio)",
          absl::StrFormat("min %.6f, mean %.6f", r.quality_min, r.quality_mean)},
         {"inverted tets", absl::StrCat(r.inverted_tets)},
         {"degenerate tets", absl::StrCat(r.degenerate_tets)},
         // verify's face check, measured anyway: `info` gave a .pvtu whose pieces each held
         // the whole mesh as three times its tets and volume, with no word (a file-format
         // sweep); refine and verify refused it.
         {"conformity", r.faces.ok() ? std::string("conformal (each interior face in two tets, "
                                                   "the boundary closed)")
                                     : std::string(r.faces.message())}});
  }
  rows.push_back({"arrays", array_text.empty() ? "none" : array_text});
  if (!file->mesh.labels.empty()) rows.push_back({"regions", RegionSummary(file->mesh.labels)});
  if (!file->dropped_arrays.empty()) {
    rows.push_back({"not read", absl::StrJoin(file->dropped_arrays, ", ")});
  }
  if (!file->skipped_cells.empty()) {
    rows.push_back({"skipped cells", absl::StrCat(io::SkippedCellsText(*file),
                                                  " (not tetrahedra: not read, not refined)")});
  }
  if (file->ghost_cells_skipped > 0) {
    rows.push_back({"ghost cells", absl::StrCat(file->ghost_cells_skipped,
                                                " skipped (VTK ghost cells: copies of another "
                                                "piece's cells)")});
  }
  rows.push_back({"frame", file->frame == io::MeshFrame::kLps   ? "LPS (SPACE=LPS tag), read as RAS"
                           : file->frame == io::MeshFrame::kRas ? "RAS (SPACE=RAS tag)"
                                                                : "untagged, taken as RAS"});
  if (!file->tet_iteration.empty()) {
    const int32_t max_iteration =
        *std::max_element(file->tet_iteration.begin(), file->tet_iteration.end());
    rows.push_back({"max iteration", absl::StrCat(max_iteration)});
  }
  PrintRows(rows);
  return kExitOk;
}

}  // namespace

const CommandSpec& InfoSpec() {
  static const CommandSpec spec{
      .name = "info",
      .summary = "Describe a volume or mesh file as tetrefine reads it",
      .usage = "tetrefine info FILE",
      .description =
          "A volume (.nii .nii.gz .hdr .nrrd .nhdr .mha .mhd .vti .pvti, a .vtk holding\n"
          "STRUCTURED_POINTS, or a DICOM series: its directory or one of its files): dims,\n"
          "voxel type, spacing, origin and world box in RAS mm, value range, the file's own\n"
          "index-to-world affine, reading warnings. A mesh (.vtu .pvtu\n"
          ".vtk .msh .mesh .meshb .ele .inp): vertices, tets, bounding box, volume, boundary\n"
          "area, mean-ratio quality, inverted tets, which arrays it carries.",
      .flags = {},
      .positional = "FILE"};
  return spec;
}

int RunInfo(const std::vector<std::string>& args) {
  int exit_code = kExitOk;
  std::optional<ParsedArgs> parsed = ParseCommandLine(InfoSpec(), args, &exit_code);
  if (!parsed.has_value()) return exit_code;
  const std::string& path = parsed->positional();
  if (IsVolumePath(path) ||
      (absl::EndsWithIgnoreCase(path, ".vtk") && io::IsVtkLegacyImage(path))) {
    return VolumeInfo(path);
  }
  if (IsMeshPath(path)) return MeshInfo(path);
  if (io::IsDicomPath(path)) return VolumeInfo(path);
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) {
    return Fail(absl::StrCat(path, ": cannot open: No such file or directory"), kExitUsage);
  }
  if (io::IsSurfacePath(path))
    return Fail(std::string(io::UnknownExtension(path).message()), kExitUsage);
  return Fail(
      absl::StrCat(path,
                   ": unknown extension: expected a volume (.nii, .nii.gz, .hdr, .nrrd, "
                   ".nhdr, .mha, .mhd, .vti, .pvti, .vtk image, a DICOM series' directory or "
                   "file) or a mesh (.vtu, .pvtu, .vtk, .msh, .mesh, .meshb, .ele, .inp)"),
      kExitUsage);
}

}  // namespace tetrefine::cli
