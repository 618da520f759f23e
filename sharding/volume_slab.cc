#include "sharding/volume_slab.h"

#include <algorithm>
#include <cmath>
#include <cstring>

#include "absl/status/status.h"
#include "absl/strings/str_cat.h"
#include "core/voxel_type.h"

namespace tetrefine::sharding {

SlabBox SlabCovering(const Volume& volume, const std::vector<Vec3>& points, bool clamp_to_grid) {
  SlabBox box{volume.lo(), volume.hi()};
  if (points.empty()) return box;
  Vec3 lo{0.0, 0.0, 0.0}, hi{0.0, 0.0, 0.0};
  for (size_t i = 0; i < points.size(); ++i) {
    Vec3 u = volume.ContinuousIndex(points[i]);
    if (clamp_to_grid) u = volume.ClampToGrid(u);
    for (int a = 0; a < 3; ++a) {
      lo[a] = i == 0 ? u[a] : std::min(lo[a], u[a]);
      hi[a] = i == 0 ? u[a] : std::max(hi[a], u[a]);
    }
  }
  for (int a = 0; a < 3; ++a) {
    // Clamped in double first: a far-away point must not overflow the conversion.
    const double limit_lo = static_cast<double>(volume.lo()[a]);
    const double limit_hi = static_cast<double>(volume.hi()[a]);
    const double first = std::clamp(std::floor(lo[a]) - 1.0, limit_lo, limit_hi);
    // The cell of hi[a] ends at sample floor(hi) + 1; one more for the margin; hi is exclusive.
    const double end = std::clamp(std::floor(hi[a]) + 3.0, limit_lo, limit_hi);
    box.lo[a] = static_cast<int64_t>(first);
    box.hi[a] = static_cast<int64_t>(end);
    // A slab holds at least one cell; widen towards whichever side has room.
    if (box.hi[a] - box.lo[a] < 2) {
      box.hi[a] = std::min(volume.hi()[a], box.lo[a] + 2);
      box.lo[a] = std::max(volume.lo()[a], box.hi[a] - 2);
    }
  }
  return box;
}

absl::StatusOr<Volume> CutSlab(const Volume& volume, const SlabBox& box) {
  const size_t voxel = VoxelSize(volume.type());
  const Index3& vlo = volume.lo();
  const Index3& vhi = volume.hi();
  const int64_t src_nx = vhi[0] - vlo[0], src_ny = vhi[1] - vlo[1];
  for (int a = 0; a < 3; ++a) {
    if (box.lo[a] < vlo[a] || box.hi[a] > vhi[a] || box.hi[a] - box.lo[a] < 2) {
      return absl::InvalidArgumentError(absl::StrCat("slab [", box.lo[a], ", ", box.hi[a],
                                                     ") on axis ", a, " is not within [", vlo[a],
                                                     ", ", vhi[a], ") or holds no cell"));
    }
  }
  const int64_t nx = box.hi[0] - box.lo[0], ny = box.hi[1] - box.lo[1], nz = box.hi[2] - box.lo[2];
  std::vector<std::byte> data(static_cast<size_t>(nx * ny * nz) * voxel);
  const std::byte* src = volume.data().data();
  const size_t row_bytes = static_cast<size_t>(nx) * voxel;
  std::byte* dst = data.data();
  for (int64_t k = box.lo[2]; k < box.hi[2]; ++k) {
    for (int64_t j = box.lo[1]; j < box.hi[1]; ++j) {
      const int64_t first = (box.lo[0] - vlo[0]) + src_nx * ((j - vlo[1]) + src_ny * (k - vlo[2]));
      std::memcpy(dst, src + static_cast<size_t>(first) * voxel, row_bytes);
      dst += row_bytes;
    }
  }
  return Volume::Create(volume.grid(), box.lo, box.hi, volume.type(), std::move(data));
}

}  // namespace tetrefine::sharding
