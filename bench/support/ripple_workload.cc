#include "bench/support/ripple_workload.h"

#include <cmath>

#include "bench/support/field_volume.h"
#include "bench/support/five_tet_lattice.h"

namespace tetrefine::bench {

RippleWorkload MakeRippleWorkload(int cells, VoxelType type) {
  GridGeometry g;
  g.dims = {128, 128, 64};
  g.spacing = {1.0, 1.0, 2.0};
  const double s = 1.5 * cells / 58.0;
  // Integer types keep 1/300 of the value's unit, plenty below any epsilon used here.
  const double scale = type == VoxelType::kFloat64 || type == VoxelType::kFloat32 ? 1.0 : 300.0;
  Volume volume = SampleField(g, type, [&](const Vec3& p) {
    return scale * 100.0 * std::sin(p[0] * 0.35 * s) * std::cos(p[1] * 0.29 * s) *
           std::sin(p[2] * 0.11 * s);
  });
  CellLattice lattice;
  lattice.cells = {cells, cells, cells};
  lattice.size = {127.0 / cells, 127.0 / cells, 126.0 / cells};
  return {std::move(volume), FiveTetLatticeMesh(lattice)};
}

}  // namespace tetrefine::bench
