#pragma once

#include <string>

#include "absl/strings/string_view.h"

namespace tetrefine::io {

// `text` made safe inside a double-quoted XML attribute or element text: & < > " become entity
// references; every other byte is copied (the writers emit UTF-8, which needs no escaping).
// Shared by the .vtu, .pvtu and .pvd writers, whose array names and file names come from users.
std::string EscapeXml(absl::string_view text);

}  // namespace tetrefine::io
