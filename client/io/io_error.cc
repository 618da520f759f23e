#include "client/io/io_error.h"

#include "absl/strings/str_cat.h"

namespace tetrefine::io {

absl::Status FileError(absl::string_view path, absl::string_view problem) {
  return absl::InvalidArgumentError(absl::StrCat(path, ": ", problem));
}

absl::Status FileLineError(absl::string_view path, int64_t line, absl::string_view problem) {
  return absl::InvalidArgumentError(absl::StrCat(path, ":", line, ": ", problem));
}

absl::Status FileUnsupported(absl::string_view path, absl::string_view problem) {
  return absl::UnimplementedError(absl::StrCat(path, ": ", problem));
}

absl::Status WithPath(absl::string_view path, const absl::Status& status) {
  if (status.ok()) return status;
  return absl::Status(status.code(), absl::StrCat(path, ": ", status.message()));
}

}  // namespace tetrefine::io
