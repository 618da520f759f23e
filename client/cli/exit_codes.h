#pragma once

#include "absl/status/status.h"
#include "absl/strings/string_view.h"

namespace tetrefine::cli {

// Exit codes shared by every subcommand, so scripts can tell a bad invocation from a bad result.
inline constexpr int kExitOk = 0;
// Ran, but the answer is "no": an invalid mesh, a server not serving, a failed refinement call.
inline constexpr int kExitFailed = 1;
// Bad flags, or an input or output file that cannot be used.
inline constexpr int kExitUsage = 2;

// Prints "tetrefine: <message>" as exactly one line on stderr (embedded newlines become "; "),
// so the failure reads the same in a terminal, a log or a container's health output.
void PrintError(absl::string_view message);

// PrintError(status.message()) and returns `exit_code`.
int Fail(const absl::Status& status, int exit_code);
int Fail(absl::string_view message, int exit_code);

// A warning line on stderr: "tetrefine: warning: <message>".
void PrintWarning(absl::string_view message);

}  // namespace tetrefine::cli
