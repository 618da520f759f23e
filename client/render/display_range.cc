#include "client/render/display_range.h"

#include <algorithm>
#include <cstdint>
#include <vector>

namespace tetrefine::render {

std::array<double, 2> DisplayRange(const Volume& volume) {
  constexpr int64_t kMaxSamples = 1'000'000;
  constexpr double kTail = 0.005;
  const Index3& lo = volume.lo();
  const Index3& hi = volume.hi();
  const int64_t nx = hi[0] - lo[0], ny = hi[1] - lo[1];
  const int64_t count = volume.voxel_count();
  const int64_t step = std::max<int64_t>(1, (count + kMaxSamples - 1) / kMaxSamples);
  std::vector<double> samples;
  samples.reserve(static_cast<size_t>(count / step + 1));
  for (int64_t index = 0; index < count; index += step) {
    const int64_t i = index % nx, j = (index / nx) % ny, k = index / (nx * ny);
    samples.push_back(volume.At(lo[0] + i, lo[1] + j, lo[2] + k));
  }
  const auto at = [&](double q) {
    const auto n = static_cast<size_t>(q * static_cast<double>(samples.size() - 1));
    std::nth_element(samples.begin(), samples.begin() + static_cast<ptrdiff_t>(n), samples.end());
    return samples[n];
  };
  const std::array<double, 2> range{at(kTail), at(1.0 - kTail)};
  if (range[1] > range[0]) return range;
  return volume.ValueRange();
}

}  // namespace tetrefine::render
