#include "tools/reproduce/phantoms.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "bench/support/five_tet_lattice.h"

namespace tetrefine::reproduce {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kOuterA = 30.0, kOuterC = 45.0;  // outer semi-axes (mm): short, long
constexpr double kInner = 0.62;                   // inner surface, as a share of the outer
constexpr double kBaseZ = 20.0;                   // base (valve) plane, heart frame (mm)
constexpr double kTiltX = 35.0 * kPi / 180.0, kTiltZ = 25.0 * kPi / 180.0;

// World -> heart frame (long axis = z, apex at z = -45 mm).
Vec3 HeartFrame(const Vec3& p) {
  const double cz = std::cos(kTiltZ), sz = std::sin(kTiltZ);
  const double x1 = cz * p[0] + sz * p[1], y1 = -sz * p[0] + cz * p[1], z1 = p[2];
  const double cx = std::cos(kTiltX), sx = std::sin(kTiltX);
  return {x1, cx * y1 + sx * z1, -sx * y1 + cx * z1};
}

// Ellipsoidal radius: 1 on the outer surface, kInner on the inner one.
double ShellRadius(const Vec3& q) {
  return std::sqrt((q[0] * q[0] + q[1] * q[1]) / (kOuterA * kOuterA) +
                   q[2] * q[2] / (kOuterC * kOuterC));
}

// 1 inside [-w, w] tapering as a raised cosine to 0 over the next `taper`.
double SmoothWindow(double x, double w, double taper) {
  const double d = std::abs(x) - w;
  if (d <= 0.0) return 1.0;
  if (d >= taper) return 0.0;
  return 0.5 * (1.0 + std::cos(kPi * d / taper));
}

GridGeometry CentredGrid(const Index3& dims, const Vec3& spacing) {
  GridGeometry g;
  g.dims = dims;
  g.spacing = spacing;
  for (int a = 0; a < 3; ++a) g.origin[a] = -0.5 * static_cast<double>(dims[a] - 1) * spacing[a];
  return g;
}

}  // namespace

double HeartPhantomValue(const Vec3& p) {
  const Vec3 q = HeartFrame(p);
  const double s = ShellRadius(q);
  // Across the wall: full at mid-wall, down to zero 0.3 (about 10 mm) beyond either surface.
  const double mid = 0.5 * (1.0 + kInner), half = 0.5 * (1.0 - kInner);
  const double wall = SmoothWindow(s - mid, 0.0, half + 0.3);
  const double base = SmoothWindow(std::max(0.0, q[2] - (kBaseZ - 8.0)), 0.0, 16.0);
  const double theta = std::atan2(q[1], q[0]);
  const double t = std::clamp((q[2] + kOuterC) / (kBaseZ + kOuterC), 0.0, 1.0);  // apex -> base
  const double regional = 0.9 + 0.1 * std::cos(theta - 0.5) * std::sin(kPi * t);
  double dtheta = std::remainder(theta + 0.5 * kPi, 2.0 * kPi);
  const double defect =
      0.65 *
      std::exp(-(dtheta * dtheta / (2 * 0.5 * 0.5) + (t - 0.45) * (t - 0.45) / (2 * 0.18 * 0.18)));
  const double heart = 100.0 * wall * base * regional * (1.0 - defect);
  const Vec3 liver{-55.0, -40.0, -30.0};
  double d2 = 0.0;
  for (int a = 0; a < 3; ++a) d2 += (p[a] - liver[a]) * (p[a] - liver[a]);
  return heart + 30.0 * std::exp(-d2 / (2.0 * 22.0 * 22.0));
}

GridGeometry Heart1Grid() { return CentredGrid({64, 64, 24}, {2.87, 2.87, 5.74}); }
GridGeometry Heart2Grid() { return CentredGrid({32, 32, 11}, {10.776, 10.776, 10.776}); }

Mesh HeartShellMesh(double cell_mm, const Vec3& box_lo, const Vec3& box_hi) {
  bench::CellLattice lattice;
  const int n = static_cast<int>(std::ceil(2.0 * 60.0 / cell_mm));
  lattice.cells = {n, n, n};
  lattice.size = {cell_mm, cell_mm, cell_mm};
  for (int a = 0; a < 3; ++a) lattice.origin[a] = -0.5 * n * cell_mm;
  auto inside_box = [&](double x, int a) { return x >= box_lo[a] && x <= box_hi[a]; };
  return bench::FiveTetLatticeMesh(lattice, [&](int i, int j, int k) {
    const int idx[3] = {i, j, k};
    Vec3 centre;
    for (int a = 0; a < 3; ++a) {
      const double lo = lattice.origin[a] + idx[a] * cell_mm;
      if (!inside_box(lo, a) || !inside_box(lo + cell_mm, a)) return false;
      centre[a] = lo + 0.5 * cell_mm;
    }
    const Vec3 q = HeartFrame(centre);
    const double s = ShellRadius(q);
    return s >= kInner && s <= 1.0 && q[2] <= kBaseZ;
  });
}

double MarschnerLobbValue(const Vec3& p) {
  constexpr double kFm = 6.0, kAlpha = 0.25;
  const double r = std::sqrt(p[0] * p[0] + p[1] * p[1]);
  const double rho = std::cos(2.0 * kPi * kFm * std::cos(kPi * r / 2.0));
  return (1.0 - std::sin(kPi * p[2] / 2.0) + kAlpha * (1.0 + rho)) / (2.0 * (1.0 + kAlpha));
}

GridGeometry MarschnerLobbGrid(int n) {
  GridGeometry g;
  g.dims = {n, n, n};
  const double h = 2.0 / (n - 1);
  g.spacing = {h, h, h};
  g.origin = {-1.0, -1.0, -1.0};
  return g;
}

}  // namespace tetrefine::reproduce
