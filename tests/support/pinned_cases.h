#pragma once

// Inputs whose paper-scheme results are pinned (tests/core/scheme_test.cc): a sharp feature that
// stops at the quality floor, a smooth one that converges, and the unstructured cube mesh.

#include <string>
#include <vector>

#include "core/mesh.h"
#include "core/refine.h"
#include "core/volume.h"

namespace tetrefine::testing {

struct PinnedCase {
  std::string name;
  Volume volume;
  Mesh mesh;
  double epsilon = 0.05;
  int max_iterations = 16;
};

// The cases, built the same way on every run (needs TETREFINE_SHARED_DATA_DIR for the cube).
std::vector<PinnedCase> PinnedCases();

}  // namespace tetrefine::testing
