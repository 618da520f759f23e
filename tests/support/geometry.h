#pragma once

#include <array>
#include <cstdint>
#include <cstdio>
#include <random>
#include <set>
#include <utility>
#include <vector>

#include "core/mesh.h"
#include "core/volume.h"
#include "core/voxel_type.h"

namespace tetrefine::testing {

// Seeds for property tests: TETREFINE_SEED in the environment pins one; otherwise `count` seeds
// starting from a fixed base. Each test prints the seed it runs with.
std::vector<uint64_t> Seeds(int count);

// A random tet with positive orientation and quality above min_quality.
std::array<Vec3, 4> RandomTet(std::mt19937_64& rng, double min_quality = 0.05);

// A uniformly random rotation (from a random unit quaternion), row-major; with `mirror` its first
// column is negated as well (det -1, as in radiological storage order).
Mat3 RandomRotation(std::mt19937_64& rng, bool mirror = false);

// A volume from a function of world position, sampled where the grid's affine puts each sample
// (for the identity direction exactly origin + index * spacing).
template <typename F>
Volume AnalyticVolume(const GridGeometry& g, F f) {
  std::vector<double> v(g.dims[0] * g.dims[1] * g.dims[2]);
  for (int64_t k = 0; k < g.dims[2]; ++k)
    for (int64_t j = 0; j < g.dims[1]; ++j)
      for (int64_t i = 0; i < g.dims[0]; ++i)
        v[i + g.dims[0] * (j + g.dims[1] * k)] = f(WorldOfIndex(
            g, {static_cast<double>(i), static_cast<double>(j), static_cast<double>(k)}));
  return *Volume::FromDoubles(g, v);
}

// The unique edges of a tet mesh as (smaller id, larger id): the reference the edge table and the
// edge-error checks are tested against.
std::set<std::pair<uint32_t, uint32_t>> UniqueEdges(const std::vector<Tet>& tets);

// A structured mesh of the box [lo, hi] with `cells` cells per axis, each cut into 5 positively
// oriented tets by core's AppendFiveTetCell (the paper's voxel tetrahedrization, the split the CLI
// mesher uses), cell (i, j, k) even when i + j + k is, so that shared faces match. Vertex
// (i, j, k) of the (cells + 1)^3 grid has id i + (cells[0] + 1) * (j + (cells[1] + 1) * k).
Mesh FiveTetMesh(const Vec3& lo, const Vec3& hi, const std::array<int, 3>& cells);

// The service tests' field: smooth, with enough curvature that refinement runs a few
// iterations.
double TestField(const Vec3& p);

// A whole volume of `dims` samples, spacing 1, origin 0, sampling TestField, stored as `type`
// (integer types round the field scaled by 100).
Volume TestVolume(const Index3& dims, VoxelType type = VoxelType::kFloat64);

// The slab [lo, hi) of TestVolume(dims, type).
Volume TestSlab(const Index3& dims, const Index3& lo, const Index3& hi,
                VoxelType type = VoxelType::kFloat64);

}  // namespace tetrefine::testing
