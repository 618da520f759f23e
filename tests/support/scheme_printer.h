#pragma once

// How GoogleTest prints a RefineScheme test parameter: by name. Without it the parameter is
// printed as raw bytes, which ctest appends to the test's name ("# GetParam() = 1-byte object
// <00>"), so `ctest -R` on the printed name finds nothing.

#include <ostream>

#include "core/refine_options.h"

namespace tetrefine {

inline void PrintTo(RefineScheme scheme, std::ostream* os) { *os << RefineSchemeName(scheme); }

}  // namespace tetrefine
