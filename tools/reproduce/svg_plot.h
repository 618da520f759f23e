#pragma once

#include <string>

#include "tools/reproduce/results.h"

namespace tetrefine::reproduce {

// A hand-written SVG of one case's refinement to convergence with the paper scheme at each
// epsilon: left, the maximum (solid) and mean (dashed) edge-midpoint error against iterations
// applied, with epsilon dotted; right, tets against iterations on a log scale, with the uniform
// baseline's tet count at equal lattice max error dashed.
std::string CasePlotSvg(const CaseRecord& c);

}  // namespace tetrefine::reproduce
