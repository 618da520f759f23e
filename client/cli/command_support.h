#pragma once

// What every subcommand does the same way: parse its flags (printing help or a one-line error)
// and load its input files with messages that name them.

#include <optional>
#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "client/cli/arg_parser.h"
#include "client/io/mesh_file.h"
#include "client/io/volume_file.h"
#include "core/volume.h"

namespace tetrefine::cli {

// Parses `args`. When the command should not go on, returns nullopt with *exit_code set: 0 after
// printing the help to stdout, kExitUsage after printing the error.
std::optional<ParsedArgs> ParseCommandLine(const CommandSpec& spec,
                                           const std::vector<std::string>& args, int* exit_code);

// io::ReadVolume / io::ReadMesh, with the flag named when the extension is not one of that kind
// (a mesh given to --volume). Errors start with the path.
absl::StatusOr<io::VolumeFile> LoadVolume(const std::string& path, const std::string& flag);
absl::StatusOr<io::MeshFile> LoadMesh(const std::string& path, const std::string& flag);

// The volume's reading warnings, one stderr line each.
void PrintVolumeWarnings(const io::VolumeFile& volume);

// Without --norm-coeff, a constant volume's errors are taken relative to 1 (its value range is
// 0): a warning naming `path` and the value says so. `range`: Volume::ValueRange().
void WarnIfConstant(const std::array<double, 2>& range, const std::string& path);

// OK when --norm-coeff `norm` suits `volume` at `epsilon` as the service checks it
// (CheckNormCoeffForRange, CheckValuePrecision); else INVALID_ARGUMENT "--norm-coeff X: ...
// (volume_path)", with the remedy a user who gave the flag has: a larger --norm-coeff or none.
// refine and verify both check it (outside reviews: refine's refusal named the mesh and the
// wire's field, and verify printed a 200-digit discrepancy and "valid").
absl::Status CheckNormCoeffFlag(double norm, const Volume& volume, double epsilon,
                                const std::string& volume_path);

}  // namespace tetrefine::cli
