#pragma once

#include <string>

#include "tools/reproduce/results.h"

namespace tetrefine::reproduce {

// Everything the report shows, as JSON (schema "tetrefine.reproduce/1"): per case its runs with
// per-iteration statistics, the uniform levels, and the section 5.1 study.
std::string ResultsJson(const ReportData& data);

}  // namespace tetrefine::reproduce
