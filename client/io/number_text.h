#pragma once

#include <cstdint>
#include <string>

#include "absl/strings/string_view.h"

namespace tetrefine::io {

// Locale-independent number parsing of a whole token (std::from_chars; a leading '+' is
// accepted). False when the token is not entirely a number or is out of range. "nan" and "inf"
// parse: callers that need finite values check.
bool ParseDouble(absl::string_view token, double& value);
bool ParseInt64(absl::string_view token, int64_t& value);

// Shortest text that parses back to exactly `value` (std::to_chars), so ASCII formats round-trip
// doubles bit for bit.
void AppendDouble(std::string& out, double value);
void AppendFloat(std::string& out, float value);

}  // namespace tetrefine::io
