#include "client/cli/file_kind.h"

#include <unistd.h>

#include <filesystem>
#include <initializer_list>

#include "absl/strings/match.h"
#include "absl/strings/str_cat.h"
#include "client/io/mesh_io.h"

namespace tetrefine::cli {
namespace {

bool EndsWithAny(const std::string& path, std::initializer_list<const char*> suffixes) {
  for (const char* suffix : suffixes) {
    if (absl::EndsWithIgnoreCase(path, suffix)) return true;
  }
  return false;
}

size_t ExtensionStart(const std::string& path) {
  const size_t slash = path.find_last_of('/');
  const size_t dot = path.find_last_of('.');
  if (dot == std::string::npos || (slash != std::string::npos && dot < slash)) {
    return std::string::npos;
  }
  // A leading dot names a hidden file, not an extension.
  if (dot == (slash == std::string::npos ? 0 : slash + 1)) return std::string::npos;
  return dot;
}

}  // namespace

bool IsVolumePath(const std::string& path) {
  return EndsWithAny(path, {".nii", ".nii.gz", ".hdr", ".hdr.gz", ".img", ".img.gz", ".nrrd",
                            ".nhdr", ".mha", ".mhd", ".vti", ".pvti"});
}

bool IsMeshPath(const std::string& path) { return io::IsMeshPath(path); }

std::string PathStem(const std::string& path) {
  const size_t dot = ExtensionStart(path);
  return dot == std::string::npos ? path : path.substr(0, dot);
}

std::string PathExtension(const std::string& path) {
  const size_t dot = ExtensionStart(path);
  return dot == std::string::npos ? std::string() : path.substr(dot);
}

std::string FileStem(const std::string& path) {
  const std::string stem = PathStem(path);
  const size_t slash = stem.find_last_of('/');
  return slash == std::string::npos ? stem : stem.substr(slash + 1);
}

absl::Status CheckOutputPath(const std::string& path, const std::string& flag, bool mesh) {
  if (path.empty()) return absl::InvalidArgumentError(absl::StrCat(flag, ": empty path"));
  if (mesh && !io::IsWritableMeshPath(path)) {
    return absl::InvalidArgumentError(
        absl::StrCat(path, ": unknown extension for a mesh (", flag,
                     "): expected .vtu, .vtk, .msh, .mesh, .meshb or .ele"));
  }
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) {
    return absl::InvalidArgumentError(absl::StrCat(path, ": is a directory (", flag, ")"));
  }
  std::filesystem::path parent = std::filesystem::path(path).parent_path();
  if (parent.empty()) parent = ".";
  if (!std::filesystem::is_directory(parent, ec)) {
    // A file where the directory should be was "does not exist" (an outside review).
    const bool exists = std::filesystem::exists(parent, ec);
    return absl::InvalidArgumentError(
        exists
            ? absl::StrCat(path, ": ", parent.string(), " is not a directory (", flag, ")")
            : absl::StrCat(path, ": directory ", parent.string(), " does not exist (", flag, ")"));
  }
  if (access(parent.c_str(), W_OK) != 0) {
    return absl::InvalidArgumentError(
        absl::StrCat(path, ": directory ", parent.string(), " is not writable (", flag, ")"));
  }
  return absl::OkStatus();
}

namespace {

// What a path names once links, "." and ".." are resolved (as far as the path exists).
std::filesystem::path FileNamedBy(const std::string& path) {
  // Absolute first: weakly_canonical leaves a relative path relative when none of it exists yet
  // ("same.vtu" against "./same.vtu").
  std::error_code ec;
  const std::filesystem::path absolute = std::filesystem::absolute(path, ec);
  if (ec) return path;
  std::filesystem::path resolved = std::filesystem::weakly_canonical(absolute, ec);
  return ec ? absolute.lexically_normal() : resolved;
}

bool IsSpecialFile(const std::filesystem::path& path) {
  std::error_code ec;
  const std::filesystem::file_status status = std::filesystem::status(path, ec);
  return !ec && (std::filesystem::is_character_file(status) || std::filesystem::is_fifo(status));
}

}  // namespace

absl::Status CheckNotTheSameFile(const NamedPath& output, const std::vector<NamedPath>& others) {
  const std::filesystem::path file = FileNamedBy(output.path);
  if (IsSpecialFile(file)) return absl::OkStatus();
  for (const NamedPath& other : others) {
    if (other.path.empty()) continue;
    // A hard link names the same file under another path: equivalent() compares the device and
    // inode of two files that exist (an outside review wrote over an input through one).
    std::error_code ec;
    if (FileNamedBy(other.path) != file && !std::filesystem::equivalent(file, other.path, ec)) {
      continue;
    }
    return absl::InvalidArgumentError(
        absl::StrCat(output.path, ": ", output.flag, " names the same file as ", other.flag,
                     other.path == output.path ? "" : absl::StrCat(" (", other.path, ")"),
                     "; writing it would overwrite that"));
  }
  return absl::OkStatus();
}

}  // namespace tetrefine::cli
