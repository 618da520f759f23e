#pragma once

#include <cstdint>

#include "absl/status/status.h"
#include "absl/strings/string_view.h"

namespace tetrefine::io {

// Every error a reader or writer returns names the file first, so a message read out of context
// (a log line, a CLI error) still says which input was bad: "<path>: <problem>".
absl::Status FileError(absl::string_view path, absl::string_view problem);

// Same, with the 1-based line number of a text file: "<path>:<line>: <problem>".
absl::Status FileLineError(absl::string_view path, int64_t line, absl::string_view problem);

// Same, for a feature the format allows but this library does not read.
absl::Status FileUnsupported(absl::string_view path, absl::string_view problem);

// Prefixes an error that came from elsewhere (e.g. Volume::Create) with the path.
absl::Status WithPath(absl::string_view path, const absl::Status& status);

}  // namespace tetrefine::io
