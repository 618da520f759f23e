#pragma once

#include <string>

#include "absl/status/statusor.h"
#include "absl/strings/string_view.h"

namespace tetrefine::io {

// True when `bytes` starts with the gzip magic number 1f 8b.
bool IsGzip(absl::string_view bytes);

// Decompresses a gzip or zlib stream (detected from its header). Concatenated gzip members are
// decoded one after another, as gunzip does. Errors carry no path: callers add it.
absl::StatusOr<std::string> Inflate(absl::string_view compressed);

// Decompresses a zlib stream whose decoded size is known, failing unless it is exactly that.
// Knowing the size lets corrupt input fail before a large allocation.
absl::StatusOr<std::string> InflateExact(absl::string_view compressed, size_t decoded_size);

// gzip-wraps `data` (for .nii.gz).
absl::StatusOr<std::string> GzipCompress(absl::string_view data);

}  // namespace tetrefine::io
