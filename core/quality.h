#pragma once

#include <cstdint>
#include <vector>

#include "core/mesh.h"
#include "core/volume.h"

namespace tetrefine {

// Mean-ratio quality (Liu and Joe; the paper's Table 7): eta = 12 (3 v)^(2/3) / sum of squared
// edge lengths. 1 for a regular tet, towards 0 for a flat one; invariant under translation,
// rotation and uniform scaling. Uses |v|.
double MeanRatio(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d);

// The same, for a caller that already has six times the signed volume.
double MeanRatioWithVolume6(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d,
                            double volume6);

// The two numbers a mean ratio is made of. For callers that compare the qualities of many tets
// (the quality guard and the choice of tiling read 5-24 children per tet): most comparisons are
// decided without the cube root, which was a tenth of a whole default-scheme call, and the answer
// is the one MeanRatio's bits give, always (tests/core/quality_test.cc).
struct MeanRatioParts {
  double volume = 0.0;  // |six times the signed volume| / 6, as MeanRatio computes it
  double sum_l2 = 0.0;  // sum of the six squared edge lengths, likewise
};

// a, b, c, d: the corners in the order MeanRatio would get them (the bits depend on the order).
MeanRatioParts MeanRatioPartsOf(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d);

// The same, for a caller that already has six times the signed volume.
MeanRatioParts MeanRatioPartsWithVolume6(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d,
                                         double volume6);

// MeanRatio's value from its parts: the same bits as MeanRatio of the same corners.
double MeanRatioOf(const MeanRatioParts& parts);

// Exactly static_cast<float>(MeanRatioOf(parts)), the per-tet quality a result carries, mostly
// without std::cbrt: see quality.cc.
float MeanRatioAsFloat(const MeanRatioParts& parts);

// MeanRatioAsFloat of parts[0, n) into out[0, n): the same values, faster for many (the loop
// overlaps the values' computations).
void MeanRatiosAsFloat(const MeanRatioParts* parts, int64_t n, float* out);

// Exactly MeanRatioOf(parts) < threshold.
bool MeanRatioBelow(const MeanRatioParts& parts, double threshold);

// Exactly the smallest MeanRatioOf(parts[i]) for i in [0, count), count >= 1.
double MinMeanRatio(const MeanRatioParts* parts, int count);

// The mean ratio of the worst tet of `tets` (1 for no tets), each measured with its corners in
// lexicographic order: the same bits whatever the order of a tet's corners (a reoriented tet
// has two swapped) or of the tets. The default of RefineOptions::quality_reference.
double QualityReference(const std::vector<Vec3>& points, const std::vector<Tet>& tets);

namespace quality_internal {
// The cube root of x > 0 (normal), to a relative error below kFastCbrtError; for
// MeanRatioAsFloat, which falls back to std::cbrt where that error could change its float.
double FastCbrt(double x);
inline constexpr double kFastCbrtError = 1e-13;
}  // namespace quality_internal

struct QualityStats {
  double min = 0.0;
  double mean = 0.0;
  int64_t count = 0;
};

}  // namespace tetrefine
