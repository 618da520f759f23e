#include "core/lattice_kernel.h"

#include <algorithm>
#include <cmath>

namespace tetrefine::lattice_internal {
namespace {

// LatticeErrors for voxel type T and a known direction branch. Two passes over the chunk: the
// positions and linear values (pure arithmetic on arrays, which the compiler vectorises), then
// the samples (gathers). The scratch is local so that the compiler knows `errors` cannot alias
// the sampler's or the map's doubles.
template <typename T, bool kAxisAligned>
void Errors(const IndexMap& map, const TrilinearSampler& sampler, const LatticePoints& points,
            const std::array<Vec3, 4>& p, const std::array<double, 4>& v, double norm,
            int64_t begin, int64_t end, double* errors) {
  const int64_t m = end - begin;
  const double* b0 = points.b(0) + begin;
  const double* b1 = points.b(1) + begin;
  const double* b2 = points.b(2) + begin;
  const double* b3 = points.b(3) + begin;
  double ux[kLatticeChunk], uy[kLatticeChunk], uz[kLatticeChunk], approx[kLatticeChunk];
  for (int64_t i = 0; i < m; ++i) {
    Vec3 x;
    for (int a = 0; a < 3; ++a) {
      // Summed from 0.0 in corner order, as the per-point loop always did (0.0 + y is not y for
      // y = -0.0, so the leading zero stays).
      double s = 0.0;
      s += b0[i] * p[0][a];
      s += b1[i] * p[1][a];
      s += b2[i] * p[2][a];
      s += b3[i] * p[3][a];
      x[a] = s;
    }
    double s = 0.0;
    s += b0[i] * v[0];
    s += b1[i] * v[1];
    s += b2[i] * v[2];
    s += b3[i] * v[3];
    approx[i] = s;
    const Vec3 u = map.Apply<kAxisAligned>(x);
    ux[i] = u[0];
    uy[i] = u[1];
    uz[i] = u[2];
  }
  double out[kLatticeChunk];
  for (int64_t i = 0; i < m; ++i) out[i] = sampler.Sample<T>({ux[i], uy[i], uz[i]}) - approx[i];
  // Apart, so that the divisions go two at a time.
  for (int64_t i = 0; i < m; ++i) out[i] = std::abs(out[i]) / norm;
  std::copy(out, out + m, errors);
}

template <bool kAxisAligned>
void ErrorsOfType(const Volume& volume, const LatticePoints& points, const std::array<Vec3, 4>& p,
                  const std::array<double, 4>& v, double norm, int64_t begin, int64_t end,
                  double* errors) {
  const IndexMap map = volume.index_map();
  const TrilinearSampler s = volume.sampler();
  switch (volume.type()) {
    case VoxelType::kUint8:
      return Errors<uint8_t, kAxisAligned>(map, s, points, p, v, norm, begin, end, errors);
    case VoxelType::kInt16:
      return Errors<int16_t, kAxisAligned>(map, s, points, p, v, norm, begin, end, errors);
    case VoxelType::kUint16:
      return Errors<uint16_t, kAxisAligned>(map, s, points, p, v, norm, begin, end, errors);
    case VoxelType::kInt32:
      return Errors<int32_t, kAxisAligned>(map, s, points, p, v, norm, begin, end, errors);
    case VoxelType::kFloat32:
      return Errors<float, kAxisAligned>(map, s, points, p, v, norm, begin, end, errors);
    case VoxelType::kFloat64:
      return Errors<double, kAxisAligned>(map, s, points, p, v, norm, begin, end, errors);
  }
  // Not a voxel type: SampleIndex reads 0 there.
  for (int64_t i = begin; i < end; ++i) {
    double approx = 0.0;
    for (int c = 0; c < 4; ++c) approx += points.b(c)[i] * v[c];
    errors[i - begin] = std::abs(0.0 - approx) / norm;
  }
}

}  // namespace

LatticePoints::LatticePoints(int n, bool with_corners) : n_(n) {
  const double inv_n = 1.0 / n;
  for (int i = 0; i <= n; ++i) {
    for (int j = 0; i + j <= n; ++j) {
      for (int k = 0; i + j + k <= n; ++k) {
        const int l = n - i - j - k;
        if (!with_corners && (i == n || j == n || k == n || l == n)) continue;
        const std::array<int, 4> ijkl = {i, j, k, l};
        for (int c = 0; c < 4; ++c) b_[c].push_back(ijkl[c] * inv_n);
        location_.push_back(LatticeLocation(n, ijkl));
      }
    }
  }
}

void LatticeErrors(const Volume& volume, const LatticePoints& points, const std::array<Vec3, 4>& p,
                   const std::array<double, 4>& v, double norm, int64_t begin, int64_t end,
                   double* errors) {
  if (volume.axis_aligned()) {
    ErrorsOfType<true>(volume, points, p, v, norm, begin, end, errors);
  } else {
    ErrorsOfType<false>(volume, points, p, v, norm, begin, end, errors);
  }
}

TetLattice ScanTetLattice(const Volume& volume, const LatticePoints& points,
                          const std::array<Vec3, 4>& p, const std::array<double, 4>& v, double norm,
                          double epsilon) {
  TetLattice out;
  double errors[kLatticeChunk];
  for (int64_t begin = 0; begin < points.size(); begin += kLatticeChunk) {
    const int64_t end = std::min(points.size(), begin + kLatticeChunk);
    LatticeErrors(volume, points, p, v, norm, begin, end, errors);
    for (int64_t i = begin; i < end; ++i) {
      const double error = errors[i - begin];
      out.sum_error += error;
      ++out.points;
      if (error > epsilon) ++out.above_epsilon;
      if (error > out.max_error || out.points == 1) {
        out.max_error = error;
        out.max_location = points.location(i);
      }
    }
  }
  return out;
}

double LatticeMaxUntil(const Volume& volume, const LatticePoints& points,
                       const std::array<Vec3, 4>& p, const std::array<double, 4>& v, double norm,
                       double epsilon) {
  // Smaller than the kernel's chunk: a failing tet often fails early, and the rest of its chunk
  // is wasted.
  constexpr int64_t kChunk = 32;
  double errors[kChunk];
  double worst = 0.0;
  for (int64_t begin = 0; begin < points.size(); begin += kChunk) {
    const int64_t end = std::min(points.size(), begin + kChunk);
    LatticeErrors(volume, points, p, v, norm, begin, end, errors);
    for (int64_t i = 0; i < end - begin; ++i) {
      worst = std::max(worst, errors[i]);
      if (worst > epsilon) return worst;
    }
  }
  return worst;
}

}  // namespace tetrefine::lattice_internal
