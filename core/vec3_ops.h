#pragma once

// The few vector operations the geometric checks share, on Vec3 (core/volume.h).

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

}  // namespace tetrefine
