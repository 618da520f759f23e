#pragma once
#include "core/refine.h"

namespace tetrefine::reproduce {

// A tetrefine refinement scheme as the reproduction runs it: a name for the report and the
// change it makes to RefineOptions (applied after epsilon, the caps and lattice_n are set).
struct Scheme {
  const char* name;
  const char* description;  // one line for the report's method section (markdown)
  void (*apply)(RefineOptions& options);
};

// Every scheme the reproduction compares, in the report's row order. A new scheme is one line
// here; the first one fills the paper's Tables 3-7 and the heart comparison.
inline constexpr Scheme kSchemes[] = {
    // Core's only scheme today. When RefineOptions gains a scheme field whose default is another
    // scheme, this entry must select the paper's explicitly.
    {"paper",
     "the paper's scheme: split the edges whose midpoint error exceeds ε, subdivide each tet by "
     "the 64-case table (core `Refine`, default options)",
     [](RefineOptions&) {}},
};

// The scheme of the paper's own tables.
inline constexpr const Scheme& kPaperScheme = kSchemes[0];

}  // namespace tetrefine::reproduce
