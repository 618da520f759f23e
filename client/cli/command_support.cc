#include "client/cli/command_support.h"

#include <cstdio>

#include "absl/strings/match.h"
#include "absl/strings/str_cat.h"
#include "client/cli/exit_codes.h"
#include "client/cli/file_kind.h"
#include "client/io/mesh_io.h"
#include "client/io/read_volume.h"

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
  return io::ReadMesh(path);
}

void PrintVolumeWarnings(const io::VolumeFile& volume) {
  for (const std::string& warning : volume.warnings) PrintWarning(warning);
}

}  // namespace tetrefine::cli
