#pragma once

#include <string>

#include "absl/strings/string_view.h"

namespace tetrefine::io {

// Standard base64 (RFC 4648, with '=' padding). Decoding is ByteStream::Base64 (byte_stream.h),
// which reads VTK's separately padded runs as one stream.
std::string Base64Encode(absl::string_view bytes);

}  // namespace tetrefine::io
