#include "client/cli/command_support.h"

#include <array>
#include <cstdio>

#include "absl/strings/match.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/strip.h"
#include "client/cli/exit_codes.h"
#include "client/cli/file_kind.h"
#include "client/io/mesh_io.h"
#include "client/io/read_volume.h"
#include "core/refine_options.h"

namespace tetrefine::cli {

std::optional<ParsedArgs> ParseCommandLine(const CommandSpec& spec,
                                           const std::vector<std::string>& args, int* exit_code) {
  absl::StatusOr<ParsedArgs> parsed = ParseArgs(spec, args);
  if (!parsed.ok()) {
    *exit_code = Fail(parsed.status(), kExitUsage);
    return std::nullopt;
  }
  if (parsed->help()) {
    std::fputs(HelpText(spec).c_str(), stdout);
    *exit_code = kExitOk;
    return std::nullopt;
  }
  return std::move(*parsed);
}

absl::StatusOr<io::VolumeFile> LoadVolume(const std::string& path, const std::string& flag) {
  // A .vtk is a mesh or an image (STRUCTURED_POINTS): the reader says which it found.
  if (IsMeshPath(path) && !absl::EndsWithIgnoreCase(path, ".vtk")) {
    return absl::InvalidArgumentError(absl::StrCat(path, ": is a mesh, but ", flag,
                                                   " takes a volume (.nii, .nii.gz, .nrrd, .nhdr, "
                                                   ".mha, .mhd, .vti, .pvti, .vtk, DICOM)"));
  }
  return io::ReadVolume(path);
}

absl::StatusOr<io::MeshFile> LoadMesh(const std::string& path, const std::string& flag) {
  if (IsVolumePath(path)) {
    return absl::InvalidArgumentError(
        absl::StrCat(path, ": is a volume, but ", flag,
                     " takes a mesh (.vtu, .pvtu, .vtk, .msh, .mesh, .meshb, .ele, .inp)"));
  }
  absl::StatusOr<io::MeshFile> file = io::ReadMesh(path);
  // A file that reads but holds no tet (an empty .inp, a .msh or .vtk without cells, a .mesh
  // with "Tetrahedra 0") was reported by `info` as a tetrahedral mesh of 0 tets in [0, 0]^3, and
  // refused only later, one command at a time, by the others (an outside review, 2026-11-28).
  if (file.ok() && file->mesh.tets.empty()) {
    return absl::InvalidArgumentError(
        absl::StrCat(path, ": no tetrahedra (", file->mesh.points.size(),
                     file->mesh.points.size() == 1 ? " vertex" : " vertices",
                     "): not a volume mesh (tetrefine reads linear tetrahedra)"));
  }
  return file;
}

absl::Status CheckNormCoeffFlag(double norm, const Volume& volume, double epsilon,
                                const std::string& volume_path) {
  const std::array<double, 2> range = volume.ValueRange();
  absl::Status fits = CheckNormCoeffForRange(norm, range);
  if (fits.ok()) fits = CheckValuePrecision(norm, range, epsilon);
  if (fits.ok()) return fits;
  absl::string_view message = fits.message();
  absl::ConsumePrefix(&message, "options.norm_coeff: ");
  absl::ConsumePrefix(&message, "volume: ");
  // The core's remedy is for a volume's own range; here the flag chose the normalisation.
  const size_t remedy = message.find("; subtract an offset");
  return absl::InvalidArgumentError(
      absl::StrCat("--norm-coeff ", norm, ": ", message.substr(0, remedy),
                   remedy == absl::string_view::npos
                       ? ""
                       : absl::StrCat("; give a larger --norm-coeff, or none for the value range (",
                                      range[1] - range[0], ")"),
                   " (", volume_path, ")"));
}

void PrintVolumeWarnings(const io::VolumeFile& volume) {
  for (const std::string& warning : volume.warnings) PrintWarning(warning);
}

void WarnIfConstant(const std::array<double, 2>& range, const std::string& path) {
  // The default normCoeff, the value range, is 0 there; 1 stands in. The help said "the volume's
  // max - min" and nothing said otherwise (an outside review, 2026-11-29).
  if (range[0] != range[1]) return;
  PrintWarning(absl::StrCat(path, ": every sample is ", range[0],
                            ": the value range is 0, so errors are taken relative to 1 "
                            "(normCoeff 1; --norm-coeff sets another)"));
}

}  // namespace tetrefine::cli
