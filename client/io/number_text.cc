#include "client/io/number_text.h"

#include <charconv>
#include <system_error>

namespace tetrefine::io {
namespace {

absl::string_view StripPlus(absl::string_view token) {
  if (token.size() > 1 && token[0] == '+') token.remove_prefix(1);
  return token;
}

template <typename T>
void AppendFloating(std::string& out, T value) {
  char buffer[64];
  const std::to_chars_result result = std::to_chars(buffer, buffer + sizeof(buffer), value);
  out.append(buffer, result.ptr);
}

}  // namespace

bool ParseDouble(absl::string_view token, double& value) {
  token = StripPlus(token);
  const char* end = token.data() + token.size();
  const std::from_chars_result result = std::from_chars(token.data(), end, value);
  return result.ec == std::errc() && result.ptr == end;
}

bool ParseInt64(absl::string_view token, int64_t& value) {
  token = StripPlus(token);
  const char* end = token.data() + token.size();
  const std::from_chars_result result = std::from_chars(token.data(), end, value);
  return result.ec == std::errc() && result.ptr == end;
}

void AppendDouble(std::string& out, double value) { AppendFloating(out, value); }

void AppendFloat(std::string& out, float value) { AppendFloating(out, value); }

}  // namespace tetrefine::io
