#pragma once

#include "core/mesh.h"
#include "core/volume.h"
#include "core/voxel_type.h"

namespace tetrefine::bench {

// The benchmarks' refinement work: a 128 x 128 x 64 volume (spacing 1, 1, 2) of smooth ripples
// and a structured 5-tets-per-cell mesh of the whole box with `cells` cells per axis
// (5 * cells^3 tets). The ripple frequency grows with `cells`, so that every mesh size sees the
// field at the same resolution relative to its cells and about the same share of edges splits
// (at kRippleEpsilon about one edge in eight; the output has ~1.95 times the input's tets from
// 10k to 1M tets, 1.73 at 10M): tets per second then compare across sizes.
struct RippleWorkload {
  Volume volume;
  Mesh mesh;
};
RippleWorkload MakeRippleWorkload(int cells, VoxelType type = VoxelType::kFloat64);

// The epsilon the benchmarks refine the ripple workload with.
inline constexpr double kRippleEpsilon = 0.05;

}  // namespace tetrefine::bench
