#pragma once

#include <cstdint>
#include <vector>

#include "tools/reproduce/cases.h"
#include "tools/reproduce/results.h"

namespace tetrefine::reproduce {

struct RunOptions {
  std::vector<double> epsilons{0.10, 0.05};
  int max_iterations = 16;  // "to convergence"; each epsilon also runs 4 iterations
  int64_t max_tets = 2'000'000;
  // Lattice statistics sample every tet of meshes up to this size (a seeded sample beyond).
  int64_t lattice_max_tets = 3'000'000;
  // No uniform level with more tets than this is built.
  int64_t uniform_cap_tets = 3'000'000;
};

// Refines the case at every epsilon (4 iterations, then max_iterations), scores each result on
// the n = 8 lattice, and refines the input uniformly until a level's lattice max and mean error
// are at most every result's (or the cap). Wall time and peak memory cover the Refine call only;
// peak memory is measured in this long-running process (process_memory.h: a lower bound).
CaseRecord RunCase(const CaseInput& input, const RunOptions& options);

}  // namespace tetrefine::reproduce
