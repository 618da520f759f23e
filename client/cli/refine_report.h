#pragma once

#include <string>

#include "core/refine.h"

namespace tetrefine::cli {

// One progress line for an iteration, as its statistics arrive:
// "iteration 2: 3176 -> 4496 tets, 723 with error, max error 0.26, mean 0.072 (0.01 s)".
std::string FormatProgressLine(const IterationStats& stats);

// The report printed when a refinement ends, in the layout of the paper's tables: discrepancy per
// iteration (INT, FNT, NTwE, max and mean error; Tables 5 and 6), tets by configuration and
// Schönhardt prisms per iteration (Tables 3 and 4), mean-ratio quality before and after
// (Table 7), then the lattice-sampled error (saying when it is a sample of the tets), the
// certified maximum (or, with `certify`, why there is none) and why refinement stopped.
std::string FormatRefineReport(const RefineResult& result, double epsilon, bool certify = false);

// A sentence for the stop reason: "converged: no edge-midpoint error above epsilon".
std::string DescribeStop(const RefineResult& result);

}  // namespace tetrefine::cli
