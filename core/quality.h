#pragma once

#include <cstdint>

#include "core/volume.h"

namespace tetrefine {

// Mean-ratio quality (Liu and Joe; the paper's Table 7): eta = 12 (3 v)^(2/3) / sum of squared
// edge lengths. 1 for a regular tet, towards 0 for a flat one; invariant under translation,
// rotation and uniform scaling. Uses |v|.
double MeanRatio(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d);

// The same, for a caller that already has six times the signed volume.
double MeanRatioWithVolume6(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d,
                            double volume6);

struct QualityStats {
  double min = 0.0;
  double mean = 0.0;
  int64_t count = 0;
};

}  // namespace tetrefine
