#pragma once

#include <cstdint>

namespace tetrefine::wire {

// What one server accepts. Checked against declared sizes before anything is allocated.
struct ServiceLimits {
  int64_t max_voxels = int64_t{1} << 28;         // voxels of the volume (slab) sent
  int64_t max_input_tets = 10'000'000;           // input tets; input vertices: 4 times this
  int64_t max_output_tets = 50'000'000;          // the largest (and default) tet budget
  int max_concurrent_refinements = 4;            // Refine calls at once
  int64_t max_message_bytes = int64_t{4} << 20;  // largest request message
};

}  // namespace tetrefine::wire
