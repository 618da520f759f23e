#pragma once

#include "core/refine_options.h"

namespace tetrefine::reproduce {

// A tetrefine refinement scheme as the reproduction runs it: a name for the report and the
// change it makes to RefineOptions (applied after epsilon, the caps and lattice_n = 0 are set:
// the reproduction scores every result itself, outside the timed call).
struct Scheme {
  const char* name;
  const char* description;  // one line for the report's method section (markdown)
  void (*apply)(RefineOptions& options);
};

// Every scheme the reproduction compares, in the report's row order. A new scheme is one entry
// here; the first one fills the paper's Tables 3-7 and the heart comparison. Each entry sets
// the scheme explicitly, so that a change of core's default changes no row.
inline constexpr Scheme kSchemes[] = {
    {"paper",
     "the paper's scheme: split the edges whose midpoint error exceeds ε, subdivide each tet by "
     "the 64-case table (`RefineScheme::kPaper`)",
     [](RefineOptions& o) { o.scheme = RefineScheme::kPaper; }},
    {"longest-edge",
     "`RefineScheme::kLongestEdge` (the default; docs/schemes.md): the "
     "paper's midpoint marks, then the longest edge of every face with a split edge (Plaza's "
     "face rule, eight rounds), and, where a split would make a much flatter child, the fewest "
     "more edges that avoid it (all six at most), once more after the last closure where that "
     "spares the tets around",
     [](RefineOptions& o) { o.scheme = RefineScheme::kLongestEdge; }},
    {"certify",
     "longest-edge with `certify`: edges judged by their exact maximum discrepancy and every tet "
     "refined until its 165-point lattice is within ε; the call includes the lattice passes and "
     "core's final lattice verification (`lattice_n` 8, its default)",
     [](RefineOptions& o) {
       o.scheme = RefineScheme::kLongestEdge;
       o.certify = true;
       o.lattice_n = 8;
     }},
};

// The scheme of the paper's own tables.
inline constexpr const Scheme& kPaperScheme = kSchemes[0];

}  // namespace tetrefine::reproduce
