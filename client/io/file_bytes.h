#pragma once

#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "absl/strings/string_view.h"
#include "client/io/temporary_files.h"

namespace tetrefine::io {

// The whole file as bytes (std::string used as a byte buffer).
absl::StatusOr<std::string> ReadFileBytes(const std::string& path);

// A whole file as read-only bytes, memory-mapped (no copy, no zero-filled buffer: a large mesh
// is parsed straight from the page cache), or read into memory where mapping fails (pipes,
// empty files). Movable, not copyable; the bytes live as long as the object.
class FileView {
 public:
  static absl::StatusOr<FileView> Open(const std::string& path);
  FileView(FileView&& other) noexcept;
  FileView& operator=(FileView&& other) noexcept;
  FileView(const FileView&) = delete;
  FileView& operator=(const FileView&) = delete;
  ~FileView();

  absl::string_view bytes() const { return bytes_; }

 private:
  FileView() = default;
  void* map_ = nullptr;
  size_t map_size_ = 0;
  std::string copy_;
  absl::string_view bytes_;
};

// The whole file, gunzipped when it starts with the gzip magic (1f 8b); otherwise as stored.
// Decided by content rather than name so a mislabelled ".nii" that is really gzip still reads.
absl::StatusOr<std::string> ReadFileMaybeGzip(const std::string& path);

// Writes `content` to a temporary file in the same directory as `path`, then renames it over
// `path`. rename() within a directory is atomic on POSIX, so readers see either the old file or
// the complete new one, and a failed write never leaves half a file behind. A symbolic link at
// `path` stays a link: the file it points to (through any chain of links) is the one replaced.
// A character device or FIFO there (/dev/null, /dev/stdout, a named pipe to another program; or a
// link to one) is written into as it is, never replaced; a directory, block device or socket is
// an error naming `path`.
absl::Status WriteFileAtomically(const std::string& path, absl::string_view content);

// Files that belong together (a .pvtu and its pieces, an --every-iteration series), written as
// WriteFileAtomically writes one but renamed into place only by Commit(), all of them, in the
// order written: a run that fails or is interrupted before Commit leaves every file it would
// have replaced as it was. Destroyed uncommitted, it removes its temporaries. A character
// device or FIFO is written into at once (nothing to rename). An outside review found a .pvtu
// re-run that ran out of disk leaving the old index over two new pieces and two old ones, and
// an interrupted --every-iteration run leaving new iteration files under the old series.
class StagedFiles {
 public:
  StagedFiles() = default;
  StagedFiles(const StagedFiles&) = delete;
  StagedFiles& operator=(const StagedFiles&) = delete;
  ~StagedFiles();

  // Writes `content` beside `path` under a temporary name; errors name `path`.
  absl::Status Write(const std::string& path, absl::string_view content);
  // Renames every staged file into place. On a failure the rest are removed and the error
  // names the file (the ones renamed before it stay: renames within a directory fail only
  // when the file system does).
  absl::Status Commit();

 private:
  struct Staged {
    std::string path, temporary, destination;
    RegisteredTemporary registration;  // until renamed or removed
  };
  std::vector<Staged> staged_;
};

}  // namespace tetrefine::io
