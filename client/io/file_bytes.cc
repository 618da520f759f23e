#include "client/io/file_bytes.h"

#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>

#include "absl/strings/str_cat.h"
#include "client/io/io_error.h"
#include "client/io/zlib_codec.h"

namespace tetrefine::io {
namespace {

absl::Status ErrnoError(absl::string_view path, absl::string_view what, int err) {
  std::string message = absl::StrCat(path, ": ", what, ": ", std::strerror(err));
  if (err == ENOENT) return absl::NotFoundError(message);
  if (err == EACCES || err == EPERM) return absl::PermissionDeniedError(message);
  return absl::InternalError(message);
}

// A name no concurrent writer in this or another process will pick.
std::string TemporaryNameFor(const std::string& path) {
  static std::atomic<uint64_t> counter{0};
  std::filesystem::path target(path);
  std::string name =
      absl::StrCat(".", target.filename().string(), ".tmp.", getpid(), ".", counter.fetch_add(1));
  return (target.parent_path() / name).string();
}

}  // namespace

absl::StatusOr<std::string> ReadFileBytes(const std::string& path) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) return FileError(path, "is a directory");
  std::FILE* file = std::fopen(path.c_str(), "rb");
  if (file == nullptr) return ErrnoError(path, "cannot open", errno);
  std::string bytes;
  char buffer[1 << 16];
  size_t n;
  while ((n = std::fread(buffer, 1, sizeof(buffer), file)) > 0) bytes.append(buffer, n);
  const bool failed = std::ferror(file) != 0;
  const int err = errno;
  std::fclose(file);
  if (failed) return ErrnoError(path, "read failed", err);
  return bytes;
}

absl::StatusOr<std::string> ReadFileMaybeGzip(const std::string& path) {
  absl::StatusOr<std::string> bytes = ReadFileBytes(path);
  if (!bytes.ok() || !IsGzip(*bytes)) return bytes;
  absl::StatusOr<std::string> inflated = Inflate(*bytes);
  if (!inflated.ok()) return WithPath(path, inflated.status());
  return inflated;
}

absl::Status WriteFileAtomically(const std::string& path, absl::string_view content) {
  const std::string temporary = TemporaryNameFor(path);
  std::FILE* file = std::fopen(temporary.c_str(), "wb");
  if (file == nullptr) return ErrnoError(path, "cannot create temporary file", errno);
  const bool written = std::fwrite(content.data(), 1, content.size(), file) == content.size();
  int err = errno;
  const bool flushed = written && std::fflush(file) == 0;
  if (written && !flushed) err = errno;
  const bool closed = std::fclose(file) == 0;
  if (written && flushed && !closed) err = errno;
  if (!written || !flushed || !closed) {
    std::remove(temporary.c_str());
    return ErrnoError(path, "write failed", err);
  }
  if (std::rename(temporary.c_str(), path.c_str()) != 0) {
    err = errno;
    std::remove(temporary.c_str());
    return ErrnoError(path, "cannot rename temporary file into place", err);
  }
  return absl::OkStatus();
}

}  // namespace tetrefine::io
