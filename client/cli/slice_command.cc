// tetrefine slice: a picture of one plane through a volume and a mesh (before and after
// refinement): the volume's trilinear values, the mesh's linear interpolation and their
// discrepancy side by side, as in the paper's Figures 15-16.

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <optional>
#include <string>
#include <vector>

#include "absl/strings/ascii.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "client/cli/command_support.h"
#include "client/cli/commands.h"
#include "client/cli/exit_codes.h"
#include "client/cli/file_kind.h"
#include "client/cli/mesh_placement.h"
#include "client/io/file_bytes.h"
#include "client/render/display_range.h"
#include "client/render/plane_section.h"
#include "client/render/slice_figure.h"
#include "client/render/slice_plane.h"
#include "client/render/slice_sampling.h"

namespace tetrefine::cli {
namespace {

constexpr int kDefaultPanelSize = 320;

struct SliceSettings {
  std::string volume_path;
  std::vector<std::string> mesh_paths;  // before, and after when given
  std::string output_path;
  int axis = 2;
  std::optional<double> position;  // unset: the middle of the volume along the axis
  int panel_size = kDefaultPanelSize;
  std::optional<double> discrepancy_max;
  bool draw_edges = true;
  bool fit_mesh_to_volume = false;  // --mesh only: the input of the refinement shown after it
};

// What to say when a file's vertex values (`file_values`, empty when it had none) differ from the
// volume's samples at the vertices (`sampled`): "differs from the volume at N of M vertices
// (largest difference D at vertex i)". The tolerance, 1e-5 of the larger of the value and
// norm_coeff, lets through a value array written as float32 or as VTK's 6-digit ASCII (an
// outside review saw a false warning for 1.6e-6 of the range), and nothing a picture could show.
// nullopt when they agree.
std::optional<std::string> DescribeValueMismatch(const std::vector<double>& file_values,
                                                 const std::vector<double>& sampled,
                                                 double norm_coeff) {
  if (file_values.size() != sampled.size()) return std::nullopt;
  int64_t differing = 0, worst = -1;
  double largest = 0.0;
  for (size_t i = 0; i < sampled.size(); ++i) {
    const double d = std::abs(file_values[i] - sampled[i]);
    if (!(d <= 1e-5 * std::max(std::abs(sampled[i]), norm_coeff))) {
      ++differing;
      if (!(d <= largest)) {
        largest = d;
        worst = static_cast<int64_t>(i);
      }
    }
  }
  if (differing == 0) return std::nullopt;
  return absl::StrFormat(
      "differs from the volume at %d of %d vertices (largest difference %.6g at vertex %d)",
      differing, sampled.size(), largest, worst);
}

// What to say when vertices of `mesh` lie outside the volume's sampled box: "N of M vertices lie
// outside the volume (first: vertex i at (x, y, z) mm; the volume spans [..] x [..] x [..] mm)".
// nullopt when none does.
std::optional<std::string> DescribeOutsideVertices(const Volume& volume, const Mesh& mesh) {
  int64_t outside = 0, first = -1;
  for (size_t i = 0; i < mesh.points.size(); ++i) {
    if (volume.Contains(volume.ContinuousIndex(mesh.points[i]))) continue;
    if (outside++ == 0) first = static_cast<int64_t>(i);
  }
  if (outside == 0) return std::nullopt;
  return absl::StrFormat("%d of %d vertices lie outside the volume (first: vertex %d %s)", outside,
                         mesh.points.size(), first, WhereOutside(volume, mesh.points[first]));
}

absl::Status SettingsFromArgs(const ParsedArgs& args, SliceSettings* s) {
  s->volume_path = *args.Get("volume");
  s->mesh_paths.push_back(*args.Get("mesh"));
  if (auto after = args.Get("mesh-after")) s->mesh_paths.push_back(*after);
  if (auto text = args.Get("axis")) {
    const std::string axis = absl::AsciiStrToLower(*text);
    if (axis != "x" && axis != "y" && axis != "z") {
      return absl::InvalidArgumentError(
          absl::StrCat("--axis: expected x, y or z, got '", *text, "'"));
    }
    s->axis = axis[0] - 'x';
  }
  if (auto text = args.Get("position")) {
    absl::StatusOr<double> p = ParseFiniteDouble("position", *text);
    if (!p.ok()) return p.status();
    s->position = *p;
  }
  if (auto text = args.Get("panel-size")) {
    absl::StatusOr<int64_t> n = ParseInteger("panel-size", *text, 8, 4096);
    if (!n.ok()) return n.status();
    s->panel_size = static_cast<int>(*n);
  }
  if (auto text = args.Get("discrepancy-max")) {
    absl::StatusOr<double> d = ParseFiniteDouble("discrepancy-max", *text);
    if (!d.ok()) return d.status();
    if (*d <= 0.0) {
      return absl::InvalidArgumentError(
          absl::StrCat("--discrepancy-max: must be > 0, got '", *text, "'"));
    }
    s->discrepancy_max = *d;
  }
  s->draw_edges = !args.Has("no-edges");
  s->fit_mesh_to_volume = args.Has("fit-mesh-to-volume");
  s->output_path = *args.Get("output");
  if (absl::AsciiStrToLower(PathExtension(s->output_path)) != ".png") {
    return absl::InvalidArgumentError(absl::StrCat(s->output_path, ": --output takes a .png file"));
  }
  return CheckOutputPath(s->output_path, "--output", /*mesh=*/false);
}

}  // namespace

const CommandSpec& SliceSpec() {
  static const CommandSpec spec{
      .name = "slice",
      .summary = "Picture of a plane: volume, mesh interpolation and discrepancy (PNG)",
      .usage =
          "tetrefine slice --volume V --mesh M [--mesh-after M2] [--axis x|y|z] [--position P]\n"
          "                       --output FIG.png [--panel-size N] [--discrepancy-max D] "
          "[--no-edges]\n"
          "                       [--fit-mesh-to-volume]",
      .description =
          "Draws, on the plane at --position mm along --axis, side by side as in the paper's\n"
          "Figures 15-16: the volume's trilinear values, the mesh's linear interpolation of its\n"
          "vertex values (the volume sampled at the vertices, as refine and verify sample them;\n"
          "a `value` array in the file that differs is named and not used), and the\n"
          "discrepancy |trilinear - linear| / (volume max - min) with its colour bar.\n"
          "Vertices outside the volume are sampled at the nearest point of its grid and named.\n"
          "The mesh's edges on the plane (the outlines of the tet sections) are drawn over the\n"
          "mesh and discrepancy panels. With --mesh-after, a second row shows that mesh (e.g.\n"
          "the refined one) on the same colour scales. Pixels no tet covers are white. The value\n"
          "colours span the volume's 0.5th to 99.5th percentile (outliers take the end colours).\n"
          "Prints the discrepancy on the plane per mesh (max, mean over covered pixels).",
      .flags =
          {
              {"volume", "FILE",
               "volume: .nii .nii.gz .hdr .nrrd .nhdr .mha .mhd .vti .pvti .vtk, DICOM series dir "
               "or file",
               true},
              {"mesh", "FILE",
               "tet mesh: .vtu .pvtu .vtk .msh .mesh .meshb .ele .inp (first row, e.g. before)",
               true},
              {"mesh-after", "FILE", "a second mesh for a second row (e.g. after refinement)"},
              {"axis", "x|y|z", "normal of the plane (default z)"},
              {"position", "P",
               "world coordinate of the plane along --axis, mm (default: the "
               "middle of the volume)"},
              {"output", "FILE", "the figure, .png", true},
              {"panel-size", "N", "pixels along the longer side of each panel (default 320)"},
              {"discrepancy-max", "D",
               "discrepancy at the top of its colour bar (default: the largest on the plane, "
               "rounded up to a round number, at least 0.01)"},
              {"no-edges", "", "do not draw the mesh's edges"},
              {"fit-mesh-to-volume", "",
               "place --mesh as refine --fit-mesh-to-volume does (for a mesh in its own unit "
               "frame); --mesh-after is drawn where it is"},
          },
      .positional = ""};
  return spec;
}

int RunSlice(const std::vector<std::string>& args) {
  int exit_code = kExitOk;
  std::optional<ParsedArgs> parsed = ParseCommandLine(SliceSpec(), args, &exit_code);
  if (!parsed.has_value()) return exit_code;
  SliceSettings s;
  if (absl::Status status = SettingsFromArgs(*parsed, &s); !status.ok()) {
    return Fail(status, kExitUsage);
  }
  absl::StatusOr<io::VolumeFile> volume_file = LoadVolume(s.volume_path, "--volume");
  if (!volume_file.ok()) return Fail(volume_file.status(), kExitUsage);
  PrintVolumeWarnings(*volume_file);
  const Volume& volume = volume_file->volume;
  std::vector<io::MeshFile> meshes;
  for (size_t i = 0; i < s.mesh_paths.size(); ++i) {
    absl::StatusOr<io::MeshFile> mesh =
        LoadMesh(s.mesh_paths[i], i == 0 ? "--mesh" : "--mesh-after");
    if (!mesh.ok()) return Fail(mesh.status(), kExitUsage);
    if (mesh->mesh.tets.empty()) {
      return Fail(absl::StrCat(s.mesh_paths[i], ": no tets"), kExitUsage);
    }
    if (i == 0 && s.fit_mesh_to_volume) {
      if (absl::Status fitted = FitMeshToVolume(volume, &mesh->mesh); !fitted.ok()) {
        return Fail(absl::StrCat(s.mesh_paths[i], ": ", fitted.message()), kExitUsage);
      }
    }
    meshes.push_back(*std::move(mesh));
  }

  // Default: the middle of the volume's world extent along the axis (for an axis-aligned grid
  // exactly the middle sample plane, as before; for an oblique one the middle of its bounds).
  const Box world = VolumeWorldBox(volume);
  const double position = s.position.value_or(
      volume.axis_aligned() ? volume.grid().origin[s.axis] +
                                  0.5 * static_cast<double>(volume.grid().dims[s.axis] - 1) *
                                      volume.grid().spacing[s.axis]
                            : 0.5 * (world[0][s.axis] + world[1][s.axis]));
  absl::StatusOr<render::SlicePlane> plane =
      render::MakeSlicePlane(volume, s.axis, position, s.panel_size);
  if (!plane.ok()) {
    return Fail(absl::StrCat(plane.status().message(), " (", s.volume_path, ")"), kExitUsage);
  }
  const std::array<double, 2> range = volume.ValueRange();
  const double norm_coeff = range[1] > range[0] ? range[1] - range[0] : 1.0;

  std::vector<render::FigureRow> rows;
  double largest = 0.0;
  const char axis_name = static_cast<char>('x' + s.axis);
  for (size_t i = 0; i < meshes.size(); ++i) {
    Mesh& mesh = meshes[i].mesh;
    // The volume's samples, not the file's `value` array: a mesh shown against another scan (or
    // a rescaled one) kept the values of the one it was refined in, and the picture showed a
    // discrepancy verify does not see (an outside review, 2026-11-28: mean 0.029 against 0.015).
    const std::vector<double> file_values = std::move(mesh.values);
    mesh.values.clear();
    mesh.values = render::VertexValues(volume, mesh);
    if (const std::optional<std::string> differs =
            DescribeValueMismatch(file_values, mesh.values, norm_coeff)) {
      PrintWarning(absl::StrCat(s.mesh_paths[i], ": the file's value array ", *differs,
                                "; the picture uses the volume's samples"));
    }
    if (const std::optional<std::string> outside = DescribeOutsideVertices(volume, mesh)) {
      PrintWarning(absl::StrCat(s.mesh_paths[i], ": ", *outside,
                                "; they are drawn with the volume's values at the nearest grid "
                                "point, and the part of the mesh outside the volume's box is not "
                                "drawn (refine and verify refuse such a mesh without --clamp)"));
    }
    render::FigureRow row;
    row.samples = render::SampleSlice(volume, mesh, *plane, norm_coeff);
    const std::string which = meshes.size() == 1 ? "" : i == 0 ? "before: " : "after: ";
    row.title = absl::StrCat(which, s.mesh_paths[i], ", ", mesh.tets.size(), " tets");
    if (row.samples.sections.empty()) {
      PrintWarning(absl::StrFormat("%s: the plane %c = %g mm cuts no tet", s.mesh_paths[i],
                                   axis_name, position));
    } else if (row.samples.covered_pixels == 0) {
      // "max 0, mean 0" alone read as a perfect mesh.
      PrintWarning(absl::StrFormat(
          "%s: the plane %c = %g mm cuts the mesh only outside the volume: no pixel has both "
          "values, so there is no discrepancy to show",
          s.mesh_paths[i], axis_name, position));
    }
    largest = std::max(largest, row.samples.max_discrepancy);
    std::printf("%s%s: %zu tets, %zu cut by the plane; ", which.c_str(), s.mesh_paths[i].c_str(),
                mesh.tets.size(), row.samples.sections.size());
    if (row.samples.covered_pixels == 0) {
      // "max 0.000000, mean 0.000000 over 0 pixels" after the warning still read as a perfect
      // mesh to a script that parses this line.
      std::printf("no discrepancy on the plane (no pixel has both values)\n");
    } else {
      std::printf("discrepancy on the plane max %.6f, mean %.6f over %lld pixels\n",
                  row.samples.max_discrepancy, row.samples.mean_discrepancy,
                  static_cast<long long>(row.samples.covered_pixels));
    }
    rows.push_back(std::move(row));
  }

  render::FigureOptions options;
  options.title = absl::StrFormat("%s, plane %c = %g mm", s.volume_path, axis_name, position);
  const std::array<double, 2> shown = render::DisplayRange(volume);
  options.value_lo = shown[0];
  options.value_hi = shown[1];
  options.discrepancy_max = s.discrepancy_max.value_or(render::DiscrepancyScale(largest));
  options.draw_edges = s.draw_edges;
  absl::StatusOr<std::string> png = render::RenderSliceFigurePng(rows, options);
  if (!png.ok())
    return Fail(absl::StrCat(s.output_path, ": ", png.status().message()), kExitFailed);
  if (absl::Status written = io::WriteFileAtomically(s.output_path, *png); !written.ok()) {
    return Fail(written, kExitUsage);
  }
  const render::FigureLayout layout =
      render::LayoutFigure(static_cast<int>(rows.size()), plane->width, plane->height);
  std::printf("Wrote %s: %d x %d pixels, plane %c = %g mm, discrepancy colour bar 0 to %g\n",
              s.output_path.c_str(), layout.width, layout.height, axis_name, position,
              options.discrepancy_max);
  return kExitOk;
}

}  // namespace tetrefine::cli
