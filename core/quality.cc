#include "core/quality.h"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <limits>
#include <utility>

#include "core/mesh.h"
#include "core/parallel.h"
#include "core/vec3_ops.h"

namespace tetrefine {
namespace {

double SquaredDistance(const Vec3& a, const Vec3& b) {
  const double dx = a[0] - b[0], dy = a[1] - b[1], dz = a[2] - b[2];
  return dx * dx + dy * dy + dz * dz;
}

MeanRatioParts PartsWithVolume6(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d,
                                double volume6) {
  return {std::abs(volume6) / 6.0, SquaredDistance(a, b) + SquaredDistance(a, c) +
                                       SquaredDistance(a, d) + SquaredDistance(b, c) +
                                       SquaredDistance(b, d) + SquaredDistance(c, d)};
}

// The cube of the mean ratio without a cube root: 12^3 * 9 v^2 / S^3. Both it and MeanRatioOf are
// computed from the same two doubles, so they differ only by the rounding of the last few
// operations (about 6 units in the last place each): where two cubes differ by more than
// kCubeMargin (relative), the mean ratios compare the same way. Far outside the range of those
// rounding errors (2^-52 = 2.2e-16 per operation), so the filter is exact, not approximate.
constexpr double kCubeMargin = 1e-12;

// True when the cube is computed without overflow, underflow or subnormals (values that no mesh
// in millimetres or metres comes near; outside, callers take the exact path).
bool CubeIsSafe(const MeanRatioParts& p) {
  return p.sum_l2 > 1e-90 && p.sum_l2 < 1e90 && p.volume > 1e-130 && p.volume < 1e130;
}

double Cube(const MeanRatioParts& p) {
  const double s = p.sum_l2;
  return 1728.0 * (9.0 * p.volume * p.volume) / (s * s * s);
}

// Sorts four points lexicographically (LexLess) with a five-comparator network: the order
// std::sort gives, without its branches on a 4-element range.
void SortLex4(std::array<Vec3, 4>& c) {
  const auto order = [&](int i, int j) {
    if (LexLess(c[j], c[i])) std::swap(c[i], c[j]);
  };
  order(0, 1);
  order(2, 3);
  order(0, 2);
  order(1, 3);
  order(1, 2);
}

}  // namespace

namespace quality_internal {

// An estimate from the bits (the exponent divided by 3, within a few percent) and two Halley
// steps, each of which about triples the correct digits. tests/core/quality_test.cc measures the
// error against long double's cbrtl over every exponent residue.
double FastCbrt(double x) {
  const uint64_t bits = std::bit_cast<uint64_t>(x);
  double y = std::bit_cast<double>(bits / 3 + 0x2a9f7893782da1ceULL);
  for (int step = 0; step < 2; ++step) {
    const double y3 = y * y * y;
    y *= (y3 + 2.0 * x) / (2.0 * y3 + x);
  }
  return y;
}

}  // namespace quality_internal

double MeanRatio(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
  return MeanRatioWithVolume6(a, b, c, d, SignedVolume6(a, b, c, d));
}

double MeanRatioWithVolume6(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d,
                            double volume6) {
  return MeanRatioOf(PartsWithVolume6(a, b, c, d, volume6));
}

MeanRatioParts MeanRatioPartsOf(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
  return PartsWithVolume6(a, b, c, d, SignedVolume6(a, b, c, d));
}

MeanRatioParts MeanRatioPartsWithVolume6(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d,
                                         double volume6) {
  return PartsWithVolume6(a, b, c, d, volume6);
}

double MeanRatioOf(const MeanRatioParts& parts) {
  if (parts.sum_l2 <= 0.0) return 0.0;
  return 12.0 * std::cbrt(9.0 * parts.volume * parts.volume) / parts.sum_l2;
}

// Every tet of a result gets its quality as a float, and std::cbrt (with the frexp and scalbn it
// calls) was 12% of a one-iteration call on 975 k tets (bench/core_bench BM_OneIteration, perf,
// 2026-11-28). Rounding to float keeps 24 bits, so a cube root good to 1e-13 decides the float
// unless the value is that close to the midpoint between two floats: r below is within
// 1e-13 + a few roundings of the exact mean ratio, and so is MeanRatioOf's value (std::cbrt is
// within an ulp or two); float rounding is monotone, so when both ends of an interval that holds
// both round to one float, MeanRatioOf's value rounds to it too. Otherwise (about one tet in
// 10^5; none of the 975 k of bench/core_bench's input), MeanRatioOf itself.
// In a loop of its own: each value is a chain of dependent divisions (about 80 cycles), which
// the processor overlaps across consecutive values only when nothing else sits between them;
// one at a time, inside the loops that read the tets, it cost what std::cbrt did.
void MeanRatiosAsFloat(const MeanRatioParts* parts, int64_t n, float* out) {
  constexpr double kMargin = 4.0 * quality_internal::kFastCbrtError;
  bool any_exact = false;
  for (int64_t i = 0; i < n; ++i) {
    const MeanRatioParts& p = parts[i];
    const bool safe = CubeIsSafe(p);
    // Unsafe parts (degenerate, huge or tiny) compute a harmless value and take the exact path.
    const double volume = safe ? p.volume : 1.0;
    const double sum_l2 = safe ? p.sum_l2 : 1.0;
    const double r = 12.0 * quality_internal::FastCbrt(9.0 * volume * volume) / sum_l2;
    const float low = static_cast<float>(r * (1.0 - kMargin));
    const float high = static_cast<float>(r * (1.0 + kMargin));
    out[i] = low;
    any_exact |= !safe || low != high;
  }
  if (!any_exact) return;
  for (int64_t i = 0; i < n; ++i) {
    const MeanRatioParts& p = parts[i];
    if (!CubeIsSafe(p)) {
      out[i] = static_cast<float>(MeanRatioOf(p));
      continue;
    }
    const double r = 12.0 * quality_internal::FastCbrt(9.0 * p.volume * p.volume) / p.sum_l2;
    if (static_cast<float>(r * (1.0 - kMargin)) != static_cast<float>(r * (1.0 + kMargin))) {
      out[i] = static_cast<float>(MeanRatioOf(p));
    }
  }
}

float MeanRatioAsFloat(const MeanRatioParts& parts) {
  float out = 0.0f;
  MeanRatiosAsFloat(&parts, 1, &out);
  return out;
}

bool MeanRatioBelow(const MeanRatioParts& parts, double threshold) {
  if (threshold > 0.0 && threshold < 1e30 && CubeIsSafe(parts)) {
    const double cube = Cube(parts);
    const double threshold_cube = threshold * threshold * threshold;
    if (cube < threshold_cube * (1.0 - kCubeMargin)) return true;
    if (cube > threshold_cube * (1.0 + kCubeMargin)) return false;
  }
  return MeanRatioOf(parts) < threshold;
}

double MinMeanRatio(const MeanRatioParts* parts, int count) {
  // The largest child count of a subdivision entry is 11; a longer list takes the exact path.
  constexpr int kMaxFiltered = 16;
  std::array<double, kMaxFiltered> cubes{};
  bool safe = count <= kMaxFiltered;
  double smallest = 0.0;
  for (int i = 0; i < count && safe; ++i) {
    safe = CubeIsSafe(parts[i]);
    cubes[i] = safe ? Cube(parts[i]) : 0.0;
    smallest = i == 0 ? cubes[i] : std::min(smallest, cubes[i]);
  }
  if (!safe) {
    double worst = MeanRatioOf(parts[0]);
    for (int i = 1; i < count; ++i) worst = std::min(worst, MeanRatioOf(parts[i]));
    return worst;
  }
  // Only a part whose cube is within the margin of the smallest can have the smallest value.
  const double bound = smallest * (1.0 + kCubeMargin);
  double worst = 2.0;  // above any mean ratio (at most 1 up to rounding)
  for (int i = 0; i < count; ++i) {
    if (cubes[i] <= bound) worst = std::min(worst, MeanRatioOf(parts[i]));
  }
  return worst;
}

double QualityReference(const std::vector<Vec3>& points, const std::vector<Tet>& tets) {
  const int64_t n = static_cast<int64_t>(tets.size());
  std::vector<double> worst(static_cast<size_t>(BlockCount(n)), 1.0);
  // Only a tet whose cube is within kCubeMargin of the smallest cube seen so far can lower the
  // minimum, so the cube root is taken for the few tets that may be the worst, not for all.
  // bench/core_bench BM_QualityReference, 975 k tets, one thread, side by side with the plain
  // minimum (2026-11-27, three runs each): the jittered mesh 56-58 -> 32-35 ms; the structured
  // one 54-55 -> 48-50 ms, since four of its tets in five are congruent with the worst one and
  // still take the root. The value is the plain minimum's, to the bit
  // (tests/core/quality_reference_test.cc).
  ForEachBlock(n, [&](int64_t b, int64_t begin, int64_t end) {
    double w = 1.0;
    double smallest_cube = std::numeric_limits<double>::infinity();
    for (int64_t t = begin; t < end; ++t) {
      std::array<Vec3, 4> c = {points[tets[t][0]], points[tets[t][1]], points[tets[t][2]],
                               points[tets[t][3]]};
      SortLex4(c);
      const MeanRatioParts parts = MeanRatioPartsOf(c[0], c[1], c[2], c[3]);
      if (CubeIsSafe(parts)) {
        const double cube = Cube(parts);
        if (cube > smallest_cube * (1.0 + kCubeMargin)) continue;
        smallest_cube = std::min(smallest_cube, cube);
      }
      w = std::min(w, MeanRatioOf(parts));
    }
    worst[b] = w;
  });
  return worst.empty() ? 1.0 : *std::min_element(worst.begin(), worst.end());
}

}  // namespace tetrefine
