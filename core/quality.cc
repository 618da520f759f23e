#include "core/quality.h"

#include <cmath>

#include "core/mesh.h"

namespace tetrefine {
namespace {

double SquaredDistance(const Vec3& a, const Vec3& b) {
  const double dx = a[0] - b[0], dy = a[1] - b[1], dz = a[2] - b[2];
  return dx * dx + dy * dy + dz * dz;
}

}  // namespace

double MeanRatio(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
  return MeanRatioWithVolume6(a, b, c, d, SignedVolume6(a, b, c, d));
}

double MeanRatioWithVolume6(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d,
                            double volume6) {
  const double volume = std::abs(volume6) / 6.0;
  const double sum_l2 = SquaredDistance(a, b) + SquaredDistance(a, c) + SquaredDistance(a, d) +
                        SquaredDistance(b, c) + SquaredDistance(b, d) + SquaredDistance(c, d);
  if (sum_l2 <= 0.0) return 0.0;
  return 12.0 * std::cbrt(9.0 * volume * volume) / sum_l2;
}

}  // namespace tetrefine
