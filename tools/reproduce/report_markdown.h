#pragma once

#include <string>

#include "tools/reproduce/results.h"

namespace tetrefine::reproduce {

// The report: what was run and how, a summary table of tetrefine against uniform refinement at
// equal error, the section 5.1 study, the paper's Tables 5-7 beside the heart phantoms, and per
// case the paper's Tables 3-7 with the lattice error, time, memory and the uniform levels. Plots
// are linked as plots/<case>.svg.
std::string ReportMarkdown(const ReportData& data);

}  // namespace tetrefine::reproduce
