#pragma once

#include <string>

#include "absl/status/statusor.h"
#include "absl/strings/string_view.h"

namespace tetrefine::io {

// Standard base64 (RFC 4648, with '=' padding).
std::string Base64Encode(absl::string_view bytes);

// Decodes base64, skipping whitespace. Each 4-character group is decoded on its own, so
// several padded blocks written back to back (as VTK does for a compressed array's header and
// data) decode as their concatenation. Fails on any other character or a partial final group.
absl::StatusOr<std::string> Base64Decode(absl::string_view text);

}  // namespace tetrefine::io
