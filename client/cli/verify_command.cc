// tetrefine verify: is a mesh a valid refinement input/output for a volume, and how far is its
// linear interpolation from the volume's trilinear one.

#include <algorithm>
#include <array>
#include <cstdio>
#include <optional>
#include <string>
#include <vector>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/strings/str_join.h"
#include "absl/strings/strip.h"
#include "client/cli/command_support.h"
#include "client/cli/commands.h"
#include "client/cli/exit_codes.h"
#include "client/cli/mesh_placement.h"
#include "client/cli/mesh_report.h"
#include "core/lattice.h"
#include "core/refine_options.h"

namespace tetrefine::cli {
namespace {

constexpr int kLatticeN = 8;
constexpr int64_t kLatticeMaxTets = 200'000;

// "tet 37: vertices 4, 9, 12, 30 at (x, y, z), ... mm": where a tet is, not only its number (an
// outside review found verify's other findings located and these not).
std::string TetWhere(const Mesh& mesh, int64_t t) {
  const Tet& tet = mesh.tets[t];
  std::vector<std::string> corners;
  for (uint32_t v : tet) {
    const Vec3& p = mesh.points[v];
    corners.push_back(absl::StrFormat("%u (%g, %g, %g)", v, p[0], p[1], p[2]));
  }
  return absl::StrCat("tet ", t, ": vertices ", absl::StrJoin(corners, ", "), " mm");
}

std::vector<std::string> Problems(const MeshReport& r, const Mesh& mesh, const Volume& volume,
                                  int64_t outside, int64_t first_outside) {
  std::vector<std::string> problems;
  if (r.duplicate_vertices > 0) {
    problems.push_back(absl::StrCat(r.duplicate_vertices, " duplicate vertices (first: ",
                                    r.first_duplicate[1], " repeats ", r.first_duplicate[0], ")"));
  }
  if (r.inverted_tets > 0) {
    problems.push_back(absl::StrCat(
        r.inverted_tets, " inverted tets (first: ", TetWhere(mesh, r.first_inverted), ")"));
  }
  if (r.degenerate_tets > 0) {
    problems.push_back(absl::StrCat(
        r.degenerate_tets, " degenerate tets (first: ", TetWhere(mesh, r.first_degenerate), ")"));
  }
  if (!r.faces.ok()) {
    // The face check skips degenerate tets, so its indices then count only the others.
    problems.push_back(absl::StrCat(r.faces.message(), r.degenerate_tets > 0
                                                           ? " (tet indices among the "
                                                             "non-degenerate tets)"
                                                           : ""));
  }
  if (outside > 0) {
    problems.push_back(absl::StrFormat(
        "%d vertices outside the volume (first: vertex %d %s; --clamp accepts them)", outside,
        first_outside, WhereOutside(volume, mesh.points[first_outside])));
  }
  return problems;
}

}  // namespace

const CommandSpec& VerifySpec() {
  static const CommandSpec spec{
      .name = "verify",
      .summary = "Check a mesh against a volume: conformity, orientation, discrepancy, quality",
      .usage = "tetrefine verify --volume V --mesh M [--epsilon E] [--norm-coeff X] [--clamp]",
      .description =
          "Valid means: every face in at most two tets with no overlap across a shared face\n"
          "and a conformal boundary: no vertex on a boundary face it is not a vertex of (a\n"
          "hanging node), every boundary edge in an even number of boundary faces, no\n"
          "boundary faces folded onto each other or closing around two overlapping tets\n"
          "(crossing diagonals), no tet of the boundary overlapping another tet (the core's\n"
          "checks, as refine runs them); no two vertices\n"
          "at the same point, no inverted or degenerate tet, every vertex inside the\n"
          "volume's world box (unless --clamp).\n"
          "Also reports total volume, boundary area, mean-ratio quality, and the discrepancy\n"
          "|trilinear - linear| / normCoeff on the 165-point barycentric lattice of every tet\n"
          "(at most 200000 tets, sampled with seed 1): max, mean and share of points above\n"
          "epsilon. The vertex values are always resampled from the volume; a `value` array in\n"
          "the file is ignored, so the numbers say how well this mesh can represent the volume.\n"
          "Exit: 0 valid, 1 not valid, 2 bad flags or unreadable input.",
      .flags =
          {
              {"volume", "FILE",
               "volume: .nii .nii.gz .hdr .nrrd .nhdr .mha .mhd .vti .pvti .vtk, DICOM series dir "
               "or file",
               true},
              {"mesh", "FILE", "tet mesh: .vtu .pvtu .vtk .msh .mesh .meshb .ele .inp", true},
              {"epsilon", "E", "tolerance for the share of lattice points above it (default 0.1)"},
              {"norm-coeff", "X", "normCoeff of the error (default: the volume's max - min)"},
              {"clamp", "",
               "accept vertices outside the volume, sampled at the nearest point of its grid, "
               "indices clamped"},
          },
      .positional = ""};
  return spec;
}

int RunVerify(const std::vector<std::string>& args) {
  int exit_code = kExitOk;
  std::optional<ParsedArgs> parsed = ParseCommandLine(VerifySpec(), args, &exit_code);
  if (!parsed.has_value()) return exit_code;
  double epsilon = 0.1;
  if (auto text = parsed->Get("epsilon")) {
    absl::StatusOr<double> e = ParseFiniteDouble("epsilon", *text);
    if (!e.ok()) return Fail(e.status(), kExitUsage);
    if (*e <= 0.0)
      return Fail(absl::StrCat("--epsilon: must be > 0, got '", *text, "'"), kExitUsage);
    epsilon = *e;
  }
  std::optional<double> norm_coeff;
  if (auto text = parsed->Get("norm-coeff")) {
    absl::StatusOr<double> x = ParseFiniteDouble("norm-coeff", *text);
    if (!x.ok()) return Fail(x.status(), kExitUsage);
    if (*x <= 0.0) {
      return Fail(absl::StrCat("--norm-coeff: must be > 0, got '", *text, "'"), kExitUsage);
    }
    norm_coeff = *x;
  }
  const bool clamp = parsed->Has("clamp");
  const std::string volume_path = *parsed->Get("volume");
  const std::string mesh_path = *parsed->Get("mesh");

  absl::StatusOr<io::VolumeFile> volume_file = LoadVolume(volume_path, "--volume");
  if (!volume_file.ok()) return Fail(volume_file.status(), kExitUsage);
  PrintVolumeWarnings(*volume_file);
  absl::StatusOr<io::MeshFile> mesh_file = LoadMesh(mesh_path, "--mesh");
  if (!mesh_file.ok()) return Fail(mesh_file.status(), kExitUsage);
  Mesh& mesh = mesh_file->mesh;
  if (mesh.tets.empty()) return Fail(absl::StrCat(mesh_path, ": no tets"), kExitUsage);
  const Volume& volume = volume_file->volume;

  const MeshReport report = AnalyzeMesh(mesh);
  int64_t outside = 0, first_outside = -1;
  mesh.values.resize(mesh.points.size());
  for (size_t i = 0; i < mesh.points.size(); ++i) {
    Vec3 u = volume.ContinuousIndex(mesh.points[i]);
    if (!volume.Contains(u)) {
      if (outside++ == 0) first_outside = static_cast<int64_t>(i);
      u = volume.ClampToGrid(u);
    }
    mesh.values[i] = volume.SampleIndex(u);
  }
  if (!norm_coeff.has_value()) {
    const std::array<double, 2> range = volume.ValueRange();
    WarnIfConstant(range, volume_path);
    norm_coeff = range[1] > range[0] ? range[1] - range[0] : 1.0;
  } else if (absl::Status norm = CheckNormCoeffFlag(*norm_coeff, volume, epsilon, volume_path);
             !norm.ok()) {
    // The bounds refine's service applies: a smaller one printed "max inf" and "valid".
    return Fail(norm, kExitUsage);
  }
  const LatticeStats lattice = SampleLattice(volume, mesh, kLatticeN, kLatticeMaxTets,
                                             /*seed=*/1, *norm_coeff, epsilon, /*clamp=*/true);

  const std::vector<std::string> problems =
      Problems(report, mesh, volume, clamp ? 0 : outside, first_outside);
  const auto count = [](int64_t n) { return absl::StrCat(n); };
  std::vector<std::vector<std::string>> rows = {
      {"mesh", absl::StrCat(mesh_path, ": ", report.vertices, " vertices, ", report.tets, " tets")},
      {"volume file", volume_path},
      {"face check", report.faces.ok()
                         ? "ok: every face in at most two tets, no overlap, no hanging node"
                         : std::string(report.faces.message())},
      {"duplicate vertices", count(report.duplicate_vertices)},
      {"inverted tets", count(report.inverted_tets)},
      {"degenerate tets", count(report.degenerate_tets)},
      {"unused vertices", count(report.unused_vertices)},
      {"vertices outside", absl::StrCat(outside, clamp && outside > 0 ? " (clamped)" : "")},
      {"mesh bounding box", FormatBox(report.bounding_box)},
      {"volume world box", FormatBox(VolumeWorldBox(volume))},
      {"total volume", absl::StrFormat("%.9g mm^3", report.volume)},
      {"boundary area",
       absl::StrFormat("%.9g mm^2 (%d faces)", report.boundary_area, report.boundary_faces)},
      {"quality (mean ratio)",
       absl::StrFormat("min %.6f, mean %.6f", report.quality_min, report.quality_mean)},
      {"discrepancy",
       absl::StrFormat("max %.6f, mean %.6f, %.4f%% of points above epsilon %g", lattice.max_error,
                       lattice.mean_error, 100.0 * lattice.share_above_epsilon, epsilon)},
      // A sample says so, as refine's line does (an outside review read the maximum of 200 000
      // of 1.3 M tets as the mesh's).
      {"lattice",
       absl::StrFormat("n = %d: %d points in %s; normCoeff %g; values resampled from the "
                       "volume",
                       lattice.n, lattice.points_sampled,
                       lattice.tets_sampled < static_cast<int64_t>(mesh.tets.size())
                           ? absl::StrFormat("a sample of %d of the %d tets (its max can be "
                                             "below the mesh's)",
                                             lattice.tets_sampled, mesh.tets.size())
                           : absl::StrFormat("every one of the %d tets", lattice.tets_sampled),
                       *norm_coeff)},
      {"result", problems.empty() ? "valid" : "NOT VALID"},
  };
  // Two columns, the names left-aligned: the table helper right-aligns, so pad by hand.
  size_t width = 0;
  for (const auto& row : rows) width = std::max(width, row[0].size());
  for (const auto& row : rows) {
    std::printf("%-*s  %s\n", static_cast<int>(width), row[0].c_str(), row[1].c_str());
  }
  if (!problems.empty()) {
    return Fail(absl::StrCat(mesh_path, ": not valid: ", absl::StrJoin(problems, "; ")),
                kExitFailed);
  }
  return kExitOk;
}

}  // namespace tetrefine::cli
