#include "client/cli/exit_codes.h"

#include <cstdio>
#include <string>

namespace tetrefine::cli {
namespace {

std::string OneLine(absl::string_view message) {
  std::string line;
  line.reserve(message.size());
  for (size_t i = 0; i < message.size(); ++i) {
    const char c = message[i];
    if (c == '\r') continue;
    if (c == '\n') {
      if (i + 1 < message.size()) line += "; ";
      continue;
    }
    line += c;
  }
  return line;
}

}  // namespace

void PrintError(absl::string_view message) {
  std::fprintf(stderr, "tetrefine: %s\n", OneLine(message).c_str());
}

int Fail(const absl::Status& status, int exit_code) {
  PrintError(status.message());
  return exit_code;
}

int Fail(absl::string_view message, int exit_code) {
  PrintError(message);
  return exit_code;
}

void PrintWarning(absl::string_view message) {
  std::fprintf(stderr, "tetrefine: warning: %s\n", OneLine(message).c_str());
}

}  // namespace tetrefine::cli
