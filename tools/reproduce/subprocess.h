#pragma once

#include <string>
#include <vector>

#include "absl/status/statusor.h"

namespace tetrefine::reproduce {

// Runs argv[0] (a path, not searched in PATH) with the arguments argv[1...], inheriting stdin,
// stdout and stderr, and waits for it. Returns its exit status; an error when it cannot be
// started or is killed by a signal (the message names the program).
absl::StatusOr<int> RunProcess(const std::vector<std::string>& argv);

}  // namespace tetrefine::reproduce
