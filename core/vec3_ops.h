#pragma once

// The few vector operations the geometric code shares, on Vec3 (core/volume.h).

#include <cmath>

#include "core/volume.h"

namespace tetrefine {

inline Vec3 Sub(const Vec3& a, const Vec3& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
inline double Dot(const Vec3& a, const Vec3& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
inline Vec3 Cross(const Vec3& a, const Vec3& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}
inline double Norm2(const Vec3& a) { return Dot(a, a); }
inline double Norm(const Vec3& a) { return std::sqrt(Dot(a, a)); }
// s x + y.
inline Vec3 Axpy(double s, const Vec3& x, const Vec3& y) {
  return {y[0] + s * x[0], y[1] + s * x[1], y[2] + s * x[2]};
}

// Lexicographic order of points: the geometric tie-break (longest edge, Steiner point order,
// segment crossings) that never depends on numbering. One definition: three files each had
// their own in an anonymous namespace, which collided when a unity build batched two of them.
inline bool LexLess(const Vec3& a, const Vec3& b) {
  if (a[0] != b[0]) return a[0] < b[0];
  if (a[1] != b[1]) return a[1] < b[1];
  return a[2] < b[2];
}

}  // namespace tetrefine
