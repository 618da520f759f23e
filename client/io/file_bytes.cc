#include "client/io/file_bytes.h"

#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <utility>

#include "absl/strings/str_cat.h"
#include "client/io/io_error.h"
#include "client/io/temporary_files.h"
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

// The file a write to `path` should replace: the end of its chain of symbolic links. Renaming
// over the link itself would turn it into a regular file and leave its target stale, where
// `cat > link` or an editor writes through it. A dangling link names the file to create. Loops
// (more than 40 links, the kernel's own limit) are left to the open to report.
std::filesystem::path FileBehindLinks(const std::string& path) {
  std::filesystem::path target(path);
  std::error_code ec;
  for (int hops = 0; hops < 40 && std::filesystem::is_symlink(target, ec); ++hops) {
    std::filesystem::path next = std::filesystem::read_symlink(target, ec);
    if (ec) break;
    target = next.is_absolute() ? next : target.parent_path() / next;
  }
  return target;
}

}  // namespace

absl::StatusOr<std::string> ReadFileBytes(const std::string& path) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) return FileError(path, "is a directory");
  std::FILE* file = std::fopen(path.c_str(), "rb");
  if (file == nullptr) return ErrnoError(path, "cannot open", errno);
  // Devices never end: /dev/zero (or a link to it named .nii) grew memory without bound until a
  // CLI sweep tried it. Regular files and pipes (process substitution, <(zcat ...)) are read.
  struct stat st;
  if (::fstat(::fileno(file), &st) == 0 &&
      (S_ISCHR(st.st_mode) || S_ISBLK(st.st_mode) || S_ISSOCK(st.st_mode))) {
    std::fclose(file);
    return FileError(path, "is a device or socket, not a file");
  }
  // One buffer of the file's size read in place: growing a string chunk by chunk copied a
  // large mesh several times over. The loop still reads to the end, for files that grow or
  // report no size (pipes).
  std::string bytes;
  size_t size = 0;
  if (std::fseek(file, 0, SEEK_END) == 0) {
    const long end = std::ftell(file);
    if (end > 0) size = static_cast<size_t>(end);
    std::rewind(file);
  }
  bytes.resize(std::max<size_t>(size, 1 << 16));
  size_t used = 0;
  size_t n;
  while ((n = std::fread(bytes.data() + used, 1, bytes.size() - used, file)) > 0) {
    used += n;
    if (used == bytes.size()) bytes.resize(2 * bytes.size());
  }
  bytes.resize(used);
  const bool failed = std::ferror(file) != 0;
  const int err = errno;
  std::fclose(file);
  if (failed) return ErrnoError(path, "read failed", err);
  return bytes;
}

absl::StatusOr<FileView> FileView::Open(const std::string& path) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) return FileError(path, "is a directory");
  FileView view;
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) return ErrnoError(path, "cannot open", errno);
  struct stat st;
  if (::fstat(fd, &st) == 0 && S_ISREG(st.st_mode) && st.st_size > 0) {
    // MAP_POPULATE: fault the pages in at once rather than one by one while parsing.
    void* map = ::mmap(nullptr, static_cast<size_t>(st.st_size), PROT_READ,
                       MAP_PRIVATE | MAP_POPULATE, fd, 0);
    if (map != MAP_FAILED) {
      view.map_ = map;
      view.map_size_ = static_cast<size_t>(st.st_size);
      view.bytes_ = absl::string_view(static_cast<const char*>(map), view.map_size_);
    }
  }
  ::close(fd);
  if (view.map_ == nullptr) {
    absl::StatusOr<std::string> bytes = ReadFileBytes(path);
    if (!bytes.ok()) return bytes.status();
    view.copy_ = *std::move(bytes);
    view.bytes_ = view.copy_;
  }
  return view;
}

FileView::FileView(FileView&& other) noexcept { *this = std::move(other); }

FileView& FileView::operator=(FileView&& other) noexcept {
  if (this == &other) return *this;
  if (map_ != nullptr) ::munmap(map_, map_size_);
  map_ = std::exchange(other.map_, nullptr);
  map_size_ = std::exchange(other.map_size_, 0);
  copy_ = std::move(other.copy_);
  bytes_ = map_ != nullptr ? std::exchange(other.bytes_, absl::string_view()) : copy_;
  other.bytes_ = absl::string_view();
  return *this;
}

FileView::~FileView() {
  if (map_ != nullptr) ::munmap(map_, map_size_);
}

absl::StatusOr<std::string> ReadFileMaybeGzip(const std::string& path) {
  absl::StatusOr<std::string> bytes = ReadFileBytes(path);
  if (!bytes.ok() || !IsGzip(*bytes)) return bytes;
  absl::StatusOr<std::string> inflated = Inflate(*bytes);
  if (!inflated.ok()) return WithPath(path, inflated.status());
  return inflated;
}

namespace {

// Writes `content` into the special file at `path` (a character device or a FIFO, or a link to
// one) as it is: opened for writing, never created, truncated or replaced.
absl::Status WriteInPlace(const std::string& path, absl::string_view content) {
  const int fd = ::open(path.c_str(), O_WRONLY | O_CLOEXEC);
  if (fd < 0) return ErrnoError(path, "cannot open for writing", errno);
  size_t done = 0;
  while (done < content.size()) {
    const ssize_t n = ::write(fd, content.data() + done, content.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      const int err = n < 0 ? errno : EIO;
      ::close(fd);
      return ErrnoError(path, "write failed", err);
    }
    done += static_cast<size_t>(n);
  }
  if (::close(fd) != 0 && errno != EINTR) return ErrnoError(path, "write failed", errno);
  return absl::OkStatus();
}

}  // namespace

namespace {

// Where `path`'s content goes: written in place (a character device or FIFO), or to a
// temporary beside the file behind its links, to be renamed over it (`temporary` and
// `destination` set).
struct Prepared {
  bool in_place = false;
  std::string temporary, destination;
  RegisteredTemporary registration;  // the temporary, for removal if a signal ends the process
};

absl::StatusOr<Prepared> WriteBeside(const std::string& path, absl::string_view content) {
  // Only a regular file (or none) is replaced. Renaming over a device or FIFO would destroy it:
  // `--output /dev/null`, or a link to it, turned /dev/null into a regular file (found by a
  // sweep as root, 2026-11-27). stat follows links as the kernel does, /proc's too: /dev/stdout
  // on a pipe is /proc/self/fd/1, a link to "pipe:[N]" that names no file.
  struct stat st;
  if (::stat(path.c_str(), &st) == 0 && !S_ISREG(st.st_mode)) {
    if (S_ISDIR(st.st_mode)) return ErrnoError(path, "cannot write", EISDIR);
    if (S_ISCHR(st.st_mode) || S_ISFIFO(st.st_mode)) {
      if (absl::Status s = WriteInPlace(path, content); !s.ok()) return s;
      return Prepared{.in_place = true, .temporary = "", .destination = "", .registration = {}};
    }
    return absl::InvalidArgumentError(absl::StrCat(
        path, ": not a regular file, character device or FIFO (",
        S_ISBLK(st.st_mode) ? "a block device" : "a socket", "): refusing to write over it"));
  }
  Prepared prepared;
  prepared.destination = FileBehindLinks(path).string();
  prepared.temporary = TemporaryNameFor(prepared.destination);
  // Registered before it exists, so that no moment of its life on disk is unregistered.
  prepared.registration = RegisteredTemporary(prepared.temporary);
  std::FILE* file = std::fopen(prepared.temporary.c_str(), "wb");
  if (file == nullptr) return ErrnoError(path, "cannot create temporary file", errno);
  // In pieces of 4 MiB: a signal handler runs only between system calls, and one write(2) of a
  // few hundred MB to a slow disk held off a user's second Ctrl-C for as long (an outside
  // review, 2026-11-29; cli/interrupt_guard.h).
  constexpr size_t kPiece = size_t{4} << 20;
  bool written = true;
  for (size_t done = 0; written && done < content.size(); done += kPiece) {
    const size_t n = std::min(kPiece, content.size() - done);
    written = std::fwrite(content.data() + done, 1, n, file) == n;
  }
  int err = errno;
  const bool flushed = written && std::fflush(file) == 0;
  if (written && !flushed) err = errno;
  const bool closed = std::fclose(file) == 0;
  if (written && flushed && !closed) err = errno;
  if (!written || !flushed || !closed) {
    std::remove(prepared.temporary.c_str());
    return ErrnoError(path, "write failed", err);
  }
  return prepared;
}

// Renames `temporary` over `destination`, or removes it when that fails. The caller's
// registration of `temporary` ends after this returns.
absl::Status RenameIntoPlace(const std::string& path, const std::string& temporary,
                             const std::string& destination) {
  if (std::rename(temporary.c_str(), destination.c_str()) != 0) {
    const int err = errno;
    std::remove(temporary.c_str());
    return ErrnoError(path, "cannot rename temporary file into place", err);
  }
  return absl::OkStatus();
}

}  // namespace

absl::Status WriteFileAtomically(const std::string& path, absl::string_view content) {
  absl::StatusOr<Prepared> prepared = WriteBeside(path, content);
  if (!prepared.ok()) return prepared.status();
  if (prepared->in_place) return absl::OkStatus();
  return RenameIntoPlace(path, prepared->temporary, prepared->destination);
}

StagedFiles::~StagedFiles() {
  for (const Staged& f : staged_) std::remove(f.temporary.c_str());
}

absl::Status StagedFiles::Write(const std::string& path, absl::string_view content) {
  absl::StatusOr<Prepared> prepared = WriteBeside(path, content);
  if (!prepared.ok()) return prepared.status();
  if (!prepared->in_place) {
    staged_.push_back(
        {path, prepared->temporary, prepared->destination, std::move(prepared->registration)});
  }
  return absl::OkStatus();
}

absl::Status StagedFiles::Commit() {
  const CommitWindow window;  // the set is renamed whole before a signal ends the process
  absl::Status first;
  for (const Staged& f : staged_) {
    if (!first.ok()) {
      std::remove(f.temporary.c_str());
      continue;
    }
    first = RenameIntoPlace(f.path, f.temporary, f.destination);
  }
  staged_.clear();
  return first;
}

}  // namespace tetrefine::io
