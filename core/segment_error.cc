#include "core/segment_error.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <utility>

#include "absl/container/inlined_vector.h"
#include "core/vec3_ops.h"

namespace tetrefine {
namespace {

// p[0] + p[1] t + p[2] t^2 + p[3] t^3 at t.
double Cubic(const std::array<double, 4>& p, double t) {
  return p[0] + t * (p[1] + t * (p[2] + t * p[3]));
}

// The trilinear field of one cell (corners c000, c100, ..., x fastest) along the local line
// (x0 + x1 t, y0 + y1 t, z0 + z1 t), as cubic coefficients in t.
std::array<double, 4> CellCubic(const std::array<double, 8>& c, const double o[3],
                                const double s[3]) {
  // f = k0 + kx x + ky y + kz z + kxy xy + kxz xz + kyz yz + kxyz xyz
  const double k0 = c[0];
  const double kx = c[1] - c[0];
  const double ky = c[2] - c[0];
  const double kz = c[4] - c[0];
  const double kxy = c[3] - c[1] - c[2] + c[0];
  const double kxz = c[5] - c[1] - c[4] + c[0];
  const double kyz = c[6] - c[2] - c[4] + c[0];
  const double kxyz = c[7] - c[3] - c[5] - c[6] + c[1] + c[2] + c[4] - c[0];
  // Products of the linear factors.
  const double xy0 = o[0] * o[1], xy1 = o[0] * s[1] + s[0] * o[1], xy2 = s[0] * s[1];
  const double xz0 = o[0] * o[2], xz1 = o[0] * s[2] + s[0] * o[2], xz2 = s[0] * s[2];
  const double yz0 = o[1] * o[2], yz1 = o[1] * s[2] + s[1] * o[2], yz2 = s[1] * s[2];
  const double xyz0 = xy0 * o[2];
  const double xyz1 = xy0 * s[2] + xy1 * o[2];
  const double xyz2 = xy1 * s[2] + xy2 * o[2];
  const double xyz3 = xy2 * s[2];
  return {k0 + kx * o[0] + ky * o[1] + kz * o[2] + kxy * xy0 + kxz * xz0 + kyz * yz0 + kxyz * xyz0,
          kx * s[0] + ky * s[1] + kz * s[2] + kxy * xy1 + kxz * xz1 + kyz * yz1 + kxyz * xyz1,
          kxy * xy2 + kxz * xz2 + kyz * yz2 + kxyz * xyz2, kxyz * xyz3};
}

// Largest |d| on [t0, t1] for the cubic d: at the ends and at the roots of d' inside.
double MaxAbsOnInterval(const std::array<double, 4>& d, double t0, double t1) {
  double best = std::max(std::abs(Cubic(d, t0)), std::abs(Cubic(d, t1)));
  // d'(t) = d1 + 2 d2 t + 3 d3 t^2
  const double qa = 3.0 * d[3], qb = 2.0 * d[2], qc = d[1];
  auto consider = [&](double t) {
    if (t > t0 && t < t1) best = std::max(best, std::abs(Cubic(d, t)));
  };
  if (qa == 0.0) {
    if (qb != 0.0) consider(-qc / qb);
    return best;
  }
  const double disc = qb * qb - 4.0 * qa * qc;
  if (disc < 0.0) return best;
  // The numerically stable pair of roots.
  const double root = std::sqrt(disc);
  const double q = -0.5 * (qb + (qb >= 0.0 ? root : -root));
  if (q != 0.0) {
    consider(q / qa);
    consider(qc / q);
  } else {
    consider(0.0);
  }
  return best;
}

}  // namespace

double MaxSegmentDiscrepancy(const Volume& volume, const Vec3& a_in, const Vec3& b_in,
                             double value_a_in, double value_b_in, bool clamp) {
  const bool swap = LexLess(b_in, a_in);
  const Vec3& a = swap ? b_in : a_in;
  const Vec3& b = swap ? a_in : b_in;
  const double value_a = swap ? value_b_in : value_a_in;
  const double value_b = swap ? value_a_in : value_b_in;
  Vec3 ua = volume.ContinuousIndex(a);
  Vec3 ub = volume.ContinuousIndex(b);
  if (clamp) {
    ua = volume.ClampToGrid(ua);
    ub = volume.ClampToGrid(ub);
  }
  const Vec3 du = {ub[0] - ua[0], ub[1] - ua[1], ub[2] - ua[2]};
  // Where the segment crosses a cell face: the field's cubic pieces end there.
  absl::InlinedVector<double, 16> breaks = {0.0, 1.0};
  for (int axis = 0; axis < 3; ++axis) {
    if (du[axis] == 0.0) continue;
    const double lo = std::min(ua[axis], ub[axis]), hi = std::max(ua[axis], ub[axis]);
    for (double k = std::floor(lo) + 1.0; k < hi; k += 1.0) {
      breaks.push_back((k - ua[axis]) / du[axis]);
    }
  }
  std::sort(breaks.begin(), breaks.end());
  const double slope = value_b - value_a;
  double best = 0.0;
  for (size_t i = 0; i + 1 < breaks.size(); ++i) {
    const double t0 = std::clamp(breaks[i], 0.0, 1.0), t1 = std::clamp(breaks[i + 1], 0.0, 1.0);
    if (!(t1 > t0)) continue;
    const double tm = 0.5 * (t0 + t1);
    const Index3 cell = volume.CellOf({ua[0] + tm * du[0], ua[1] + tm * du[1], ua[2] + tm * du[2]});
    const double origin[3] = {ua[0] - static_cast<double>(cell[0]),
                              ua[1] - static_cast<double>(cell[1]),
                              ua[2] - static_cast<double>(cell[2])};
    const double step[3] = {du[0], du[1], du[2]};
    std::array<double, 4> d = CellCubic(volume.CellCorners(cell), origin, step);
    d[0] -= value_a;
    d[1] -= slope;
    best = std::max(best, MaxAbsOnInterval(d, t0, t1));
  }
  return best;
}

}  // namespace tetrefine
