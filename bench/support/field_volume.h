#pragma once

#include <cstdint>
#include <vector>

#include "core/volume.h"
#include "core/voxel_type.h"

namespace tetrefine::bench {

// Stores `values` (x fastest, then y, then z) as `type`: integer types get the value rounded and
// clamped to the type's range. Aborts on a geometry Volume::Create refuses (a generator bug).
Volume VolumeFromValues(const GridGeometry& grid, VoxelType type,
                        const std::vector<double>& values);

// Samples f(world position) at every grid point (oblique grids included).
template <typename F>
Volume SampleField(const GridGeometry& g, VoxelType type, F f) {
  std::vector<double> v;
  v.reserve(static_cast<size_t>(g.dims[0] * g.dims[1] * g.dims[2]));
  for (int64_t k = 0; k < g.dims[2]; ++k) {
    for (int64_t j = 0; j < g.dims[1]; ++j) {
      for (int64_t i = 0; i < g.dims[0]; ++i) {
        // Through the grid's affine (for the identity exactly origin + index * spacing).
        v.push_back(f(WorldOfIndex(
            g, {static_cast<double>(i), static_cast<double>(j), static_cast<double>(k)})));
      }
    }
  }
  return VolumeFromValues(g, type, v);
}

}  // namespace tetrefine::bench
