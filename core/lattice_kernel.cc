#include "core/lattice_kernel.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <type_traits>

#if defined(__x86_64__)
#include <immintrin.h>
#endif

namespace tetrefine::lattice_internal {
namespace {

// The first pass of LatticeErrors over a chunk: positions mapped to continuous grid indices
// and the linear values, pure arithmetic on arrays, which the compiler vectorises.
template <bool kAxisAligned>
[[gnu::always_inline]] inline void IndicesAndValues(const IndexMap& map,
                                                    const LatticePoints& points,
                                                    const std::array<Vec3, 4>& p,
                                                    const std::array<double, 4>& v, int64_t begin,
                                                    int64_t m, double* ux, double* uy, double* uz,
                                                    double* approx) {
  const double* b0 = points.b(0) + begin;
  const double* b1 = points.b(1) + begin;
  const double* b2 = points.b(2) + begin;
  const double* b3 = points.b(3) + begin;
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
}

// LatticeErrors for voxel type T and a known direction branch. Two passes over the chunk: the
// positions and linear values, then the samples (gathers). The scratch is local so that the
// compiler knows `errors` cannot alias the sampler's or the map's doubles.
template <typename T, bool kAxisAligned>
void Errors(const IndexMap& map, const TrilinearSampler& sampler, const LatticePoints& points,
            const std::array<Vec3, 4>& p, const std::array<double, 4>& v, double norm,
            int64_t begin, int64_t end, double* errors) {
  const int64_t m = end - begin;
  double ux[kLatticeChunk], uy[kLatticeChunk], uz[kLatticeChunk], approx[kLatticeChunk];
  IndicesAndValues<kAxisAligned>(map, points, p, v, begin, m, ux, uy, uz, approx);
  double out[kLatticeChunk];
  for (int64_t i = 0; i < m; ++i) out[i] = sampler.Sample<T>({ux[i], uy[i], uz[i]}) - approx[i];
  // Apart, so that the divisions go two at a time.
  for (int64_t i = 0; i < m; ++i) out[i] = std::abs(out[i]) / norm;
  std::copy(out, out + m, errors);
}

// Calls f(T{}) with T the C++ type of `type` (uint8_t, int16_t, uint16_t, int32_t, float,
// double); false, without a call, when `type` is not a voxel type.
template <typename F>
bool WithVoxelType(VoxelType type, F&& f) {
  switch (type) {
    case VoxelType::kUint8:
      f(uint8_t{});
      return true;
    case VoxelType::kInt16:
      f(int16_t{});
      return true;
    case VoxelType::kUint16:
      f(uint16_t{});
      return true;
    case VoxelType::kInt32:
      f(int32_t{});
      return true;
    case VoxelType::kFloat32:
      f(float{});
      return true;
    case VoxelType::kFloat64:
      f(double{});
      return true;
  }
  return false;
}

#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#define TETREFINE_LATTICE_AVX2 1

// Errors with AVX2, four points at a time: the same operations in the same order on each point
// (no fused multiply-add: the target is avx2 alone and the build passes -ffp-contract=off), so the
// same bits; tests/core/lattice_kernel_test.cc compares both paths with the point-by-point scan.
// The voxel reads stay scalar (AVX2's gathers read 4 or 8 bytes, past the end of a slab of
// 1- or 2-byte voxels); the clamps, the cell and weight arithmetic and the seven
// interpolations run on vectors. Measured 2026-11-25 (bench/sampling_bench BM_Lattice, int16,
// one thread, interleaved): see the commit that added it.
// Usable when the grid's cell arithmetic fits 32-bit lanes and every slab axis has a cell.
bool FitsAvx2(const TrilinearSampler& s) {
  for (int a = 0; a < 3; ++a) {
    if (s.max_index[a] >= 2147483647.0 || s.max_cell[a] < s.lo[a]) return false;
  }
  return s.dy < (int64_t{1} << 31) && s.dz < (int64_t{1} << 31);
}

// volume_internal::Lerp on four lanes: a (1 - w) + b w.
[[gnu::target("avx2"), gnu::always_inline]] inline __m256d Lerp4(__m256d a, __m256d b, __m256d w,
                                                                 __m256d one) {
  return _mm256_add_pd(_mm256_mul_pd(a, _mm256_sub_pd(one, w)), _mm256_mul_pd(b, w));
}

// The 8 corners of four cells whose first samples are at `base` (x, then y, then z neighbours, as
// TrilinearSampler::Sample reads them), as doubles. The conversions are exact, so the load order
// does not change a bit. For 2-byte voxels (CT and MRI's int16 and uint16) one 4-byte gather reads
// a sample and its x neighbour, which is always in the slab (FitsAvx2: every axis has a cell).
// Measured 2026-11-27, bench/sampling_bench BM_Lattice, one thread, AMD EPYC (Zen 4),
// interleaved: int16 296-319 ms scalar, 274-291 ms gathered. Not for other types: 8-byte gathers
// for float64 measured slower than scalar loads (235-253 ms against 288-304), and for 1-byte
// voxels a 4-byte gather would read up to 2 bytes past the slab's last sample.
template <typename T>
[[gnu::target("avx2"), gnu::always_inline]] inline void LoadCorners4(const TrilinearSampler& s,
                                                                     __m256i base,
                                                                     __m256d corner[8]) {
  const int64_t pair_step[4] = {0, s.dy, s.dz, s.dz + s.dy};
  if constexpr (sizeof(T) == 2) {
    const int* data = reinterpret_cast<const int*>(s.data);
    for (int k = 0; k < 4; ++k) {
      const __m256i index = _mm256_add_epi64(base, _mm256_set1_epi64x(pair_step[k]));
      const __m128i pair = _mm256_i64gather_epi32(data, index, 2);
      // Little-endian: the low half is the cell's sample, the high half its x neighbour.
      const __m128i first = std::is_signed_v<T> ? _mm_srai_epi32(_mm_slli_epi32(pair, 16), 16)
                                                : _mm_and_si128(pair, _mm_set1_epi32(0xffff));
      const __m128i second =
          std::is_signed_v<T> ? _mm_srai_epi32(pair, 16) : _mm_srli_epi32(pair, 16);
      corner[2 * k] = _mm256_cvtepi32_pd(first);
      corner[2 * k + 1] = _mm256_cvtepi32_pd(second);
    }
  } else {
    alignas(32) int64_t index[4];
    _mm256_store_si256(reinterpret_cast<__m256i*>(index), base);
    alignas(32) double c[8][4];
    const int64_t step[8] = {0, 1, s.dy, s.dy + 1, s.dz, s.dz + 1, s.dz + s.dy, s.dz + s.dy + 1};
    for (int k = 0; k < 8; ++k) {
      for (int j = 0; j < 4; ++j) c[k][j] = volume_internal::Load<T>(s.data, index[j] + step[k]);
    }
    for (int k = 0; k < 8; ++k) corner[k] = _mm256_load_pd(c[k]);
  }
}

template <typename T>
[[gnu::target("avx2"), gnu::always_inline]] inline void SampleAvx2(const TrilinearSampler& s,
                                                                   const double* ux,
                                                                   const double* uy,
                                                                   const double* uz, int64_t m,
                                                                   double* out) {
  const double* u[3] = {ux, uy, uz};
  const __m256d zero = _mm256_setzero_pd();
  const __m256d one = _mm256_set1_pd(1.0);
  __m256d hi[3];
  __m128i lo[3], max_cell[3];
  for (int a = 0; a < 3; ++a) {
    hi[a] = _mm256_set1_pd(s.max_index[a]);
    lo[a] = _mm_set1_epi32(static_cast<int32_t>(s.lo[a]));
    max_cell[a] = _mm_set1_epi32(static_cast<int32_t>(s.max_cell[a]));
  }
  const __m256i dy = _mm256_set1_epi64x(s.dy), dz = _mm256_set1_epi64x(s.dz);
  int64_t i = 0;
  for (; i + 4 <= m; i += 4) {
    __m256d t[3];
    __m256i offset[3];
    for (int a = 0; a < 3; ++a) {
      // std::clamp(u, 0, max_index): max(0, u) keeps u on ties (so -0.0 stays -0.0), then
      // min(max_index, .) likewise.
      const __m256d x = _mm256_min_pd(hi[a], _mm256_max_pd(zero, _mm256_loadu_pd(u[a] + i)));
      // x is in [0, 2^31): truncation to 32 bits is the scalar path's floor.
      const __m128i c = _mm_min_epi32(_mm_max_epi32(_mm256_cvttpd_epi32(x), lo[a]), max_cell[a]);
      t[a] = _mm256_sub_pd(x, _mm256_cvtepi32_pd(c));
      offset[a] = _mm256_cvtepi32_epi64(_mm_sub_epi32(c, lo[a]));
    }
    const __m256i base =
        _mm256_add_epi64(_mm256_add_epi64(offset[0], _mm256_mul_epi32(dy, offset[1])),
                         _mm256_mul_epi32(dz, offset[2]));
    __m256d corner[8];
    LoadCorners4<T>(s, base, corner);
    const __m256d c00 = Lerp4(corner[0], corner[1], t[0], one);
    const __m256d c10 = Lerp4(corner[2], corner[3], t[0], one);
    const __m256d c01 = Lerp4(corner[4], corner[5], t[0], one);
    const __m256d c11 = Lerp4(corner[6], corner[7], t[0], one);
    const __m256d value = Lerp4(Lerp4(c00, c10, t[1], one), Lerp4(c01, c11, t[1], one), t[2], one);
    _mm256_storeu_pd(out + i, value);
  }
  for (; i < m; ++i) out[i] = s.Sample<T>({ux[i], uy[i], uz[i]});
}

template <typename T>
[[gnu::target("avx2")]] void SampleManyAvx2(const TrilinearSampler& s, const double* ux,
                                            const double* uy, const double* uz, int64_t m,
                                            double* out) {
  SampleAvx2<T>(s, ux, uy, uz, m, out);
}

template <typename T, bool kAxisAligned>
[[gnu::target("avx2")]] void ErrorsAvx2(const IndexMap& map, const TrilinearSampler& sampler,
                                        const LatticePoints& points, const std::array<Vec3, 4>& p,
                                        const std::array<double, 4>& v, double norm, int64_t begin,
                                        int64_t end, double* errors) {
  const int64_t m = end - begin;
  double ux[kLatticeChunk], uy[kLatticeChunk], uz[kLatticeChunk], approx[kLatticeChunk];
  IndicesAndValues<kAxisAligned>(map, points, p, v, begin, m, ux, uy, uz, approx);
  double out[kLatticeChunk];
  SampleAvx2<T>(sampler, ux, uy, uz, m, out);
  for (int64_t i = 0; i < m; ++i) out[i] = std::abs(out[i] - approx[i]) / norm;
  std::copy(out, out + m, errors);
}

std::atomic<bool>& SimdSwitch() {
  static std::atomic<bool> on(__builtin_cpu_supports("avx2") != 0);
  return on;
}
#endif

template <bool kAxisAligned>
void ErrorsOfType(const Volume& volume, const LatticePoints& points, const std::array<Vec3, 4>& p,
                  const std::array<double, 4>& v, double norm, int64_t begin, int64_t end,
                  double* errors) {
  const IndexMap map = volume.index_map();
  const TrilinearSampler s = volume.sampler();
#ifdef TETREFINE_LATTICE_AVX2
  if (SimdSwitch().load(std::memory_order_relaxed) && FitsAvx2(s) &&
      WithVoxelType(volume.type(), [&](auto voxel) {
        ErrorsAvx2<decltype(voxel), kAxisAligned>(map, s, points, p, v, norm, begin, end, errors);
      })) {
    return;
  }
#endif
  if (WithVoxelType(volume.type(), [&](auto voxel) {
        Errors<decltype(voxel), kAxisAligned>(map, s, points, p, v, norm, begin, end, errors);
      })) {
    return;
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

bool LatticeSimd() {
#ifdef TETREFINE_LATTICE_AVX2
  return SimdSwitch().load(std::memory_order_relaxed);
#else
  return false;
#endif
}

bool SetLatticeSimdForTesting(bool on) {
#ifdef TETREFINE_LATTICE_AVX2
  if (on && __builtin_cpu_supports("avx2") == 0) return false;
  SimdSwitch().store(on, std::memory_order_relaxed);
  return true;
#else
  return !on;
#endif
}

void SampleIndices(const Volume& volume, const double* ux, const double* uy, const double* uz,
                   int64_t count, double* out) {
  const TrilinearSampler s = volume.sampler();
#ifdef TETREFINE_LATTICE_AVX2
  if (SimdSwitch().load(std::memory_order_relaxed) && FitsAvx2(s) &&
      WithVoxelType(volume.type(), [&](auto voxel) {
        SampleManyAvx2<decltype(voxel)>(s, ux, uy, uz, count, out);
      })) {
    return;
  }
#endif
  for (int64_t i = 0; i < count; ++i) out[i] = volume.SampleIndex({ux[i], uy[i], uz[i]});
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

LatticeCheck CheckLatticeUntil(const Volume& volume, const LatticePoints& points,
                               const std::array<Vec3, 4>& p, const std::array<double, 4>& v,
                               double norm, double epsilon) {
  // Smaller than the kernel's chunk: a failing tet often fails early, and the rest of its chunk
  // is wasted.
  constexpr int64_t kChunk = 32;
  double errors[kChunk];
  LatticeCheck out;
  for (int64_t begin = 0; begin < points.size(); begin += kChunk) {
    const int64_t end = std::min(points.size(), begin + kChunk);
    LatticeErrors(volume, points, p, v, norm, begin, end, errors);
    for (int64_t i = 0; i < end - begin; ++i) {
      out.max_error = std::max(out.max_error, errors[i]);
      out.sum_error += errors[i];
      if (errors[i] > epsilon) {
        out.passed = false;
        return out;
      }
    }
  }
  return out;
}

}  // namespace tetrefine::lattice_internal
