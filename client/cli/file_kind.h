#pragma once

#include <string>
#include <vector>

#include "absl/status/status.h"

namespace tetrefine::cli {

// By extension, case-insensitive, exactly as client/io dispatches: a volume (.nii, .nii.gz, .hdr,
// .hdr.gz, .nrrd, .nhdr, .mha, .mhd, .vti, .pvti) or a mesh (.vtu, .pvtu, .vtk, .msh, .mesh,
// .meshb, .ele, .inp).
bool IsVolumePath(const std::string& path);
bool IsMeshPath(const std::string& path);

// "dir/brain.refined.vtu" -> "dir/brain.refined"; the extension is the last ".xyz" of the file
// name (none: the path itself).
std::string PathStem(const std::string& path);
// "dir/brain.refined.vtu" -> ".vtu" (empty when the name has no dot).
std::string PathExtension(const std::string& path);
// The file name without directory and extension: "dir/cube.mesh" -> "cube".
std::string FileStem(const std::string& path);

// Checks, before any work is done, that a file can be created at `path`: a mesh extension when
// `mesh` is set, a directory that exists, and no directory of that name. The message names the
// path and the flag.
absl::Status CheckOutputPath(const std::string& path, const std::string& flag, bool mesh);

// A file a command names by a flag: {"--stats-json", "run.json"}.
struct NamedPath {
  std::string flag;
  std::string path;
};
// Checks that `output` names a file that none of `others` names (through symbolic and hard links,
// "./" and the like: the same file, not the same string), so that one output cannot overwrite
// another or an input. Character devices and FIFOs (/dev/null for two outputs) may be shared. The
// message names both flags and the path.
absl::Status CheckNotTheSameFile(const NamedPath& output, const std::vector<NamedPath>& others);

}  // namespace tetrefine::cli
