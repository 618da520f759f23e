#include "tools/reproduce/otsu_threshold.h"

#include <array>
#include <cstdint>

namespace tetrefine::reproduce {

double OtsuThreshold(const Volume& volume) {
  const auto [lo, hi] = volume.ValueRange();
  if (!(hi > lo)) return lo;
  constexpr int kBins = 256;
  const double width = (hi - lo) / kBins;
  std::array<int64_t, kBins> histogram{};
  const Index3& a = volume.lo();
  const Index3& b = volume.hi();
  for (int64_t k = a[2]; k < b[2]; ++k) {
    for (int64_t j = a[1]; j < b[1]; ++j) {
      for (int64_t i = a[0]; i < b[0]; ++i) {
        int bin = static_cast<int>((volume.At(i, j, k) - lo) / width);
        if (bin >= kBins) bin = kBins - 1;
        ++histogram[bin];
      }
    }
  }
  double total = 0.0, weighted = 0.0;
  for (int i = 0; i < kBins; ++i) {
    total += static_cast<double>(histogram[i]);
    weighted += static_cast<double>(histogram[i]) * (i + 0.5);
  }
  double below = 0.0, below_weighted = 0.0, best = -1.0;
  int best_bin = 0;
  for (int i = 0; i < kBins - 1; ++i) {
    below += static_cast<double>(histogram[i]);
    below_weighted += static_cast<double>(histogram[i]) * (i + 0.5);
    const double above = total - below;
    if (below == 0.0 || above == 0.0) continue;
    const double mean_below = below_weighted / below;
    const double mean_above = (weighted - below_weighted) / above;
    const double between = below * above * (mean_below - mean_above) * (mean_below - mean_above);
    if (between > best) {
      best = between;
      best_bin = i;
    }
  }
  // The boundary between bin best_bin and the next.
  return lo + (best_bin + 1) * width;
}

}  // namespace tetrefine::reproduce
