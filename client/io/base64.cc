#include "client/io/base64.h"

#include "absl/strings/escaping.h"

namespace tetrefine::io {

std::string Base64Encode(absl::string_view bytes) { return absl::Base64Escape(bytes); }

}  // namespace tetrefine::io
