// The lattice kernel (core/lattice_kernel.h) against the point-by-point scan it replaced: every
// statistic equal to the bit, for every voxel type, clamp on and off, identity and oblique
// directions, whole volumes and slabs, lattice orders 1, 2, 8 and 13, and certified mode's
// early-stopping maximum likewise.
#include "core/lattice_kernel.h"

#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <cstring>
#include <functional>
#include <limits>
#include <random>
#include <vector>

#include "core/lattice.h"
#include "tests/support/geometry.h"

namespace tetrefine {
namespace {

// SampleTetLattice as it was before the kernel (commit 77d81d7), verbatim: the reference.
TetLattice ReferenceTetLattice(const Volume& volume, const Mesh& mesh, int64_t t, int n,
                               double norm_coeff, double epsilon, bool clamp) {
  const Tet& tet = mesh.tets[t];
  const Vec3* p[4] = {&mesh.points[tet[0]], &mesh.points[tet[1]], &mesh.points[tet[2]],
                      &mesh.points[tet[3]]};
  const double v[4] = {mesh.values[tet[0]], mesh.values[tet[1]], mesh.values[tet[2]],
                       mesh.values[tet[3]]};
  TetLattice out;
  const double inv_n = 1.0 / n;
  for (int i = 0; i <= n; ++i) {
    for (int j = 0; i + j <= n; ++j) {
      for (int k = 0; i + j + k <= n; ++k) {
        const int l = n - i - j - k;
        const double b[4] = {i * inv_n, j * inv_n, k * inv_n, l * inv_n};
        Vec3 x{0, 0, 0};
        double approx = 0.0;
        for (int c = 0; c < 4; ++c) {
          for (int a = 0; a < 3; ++a) x[a] += b[c] * (*p[c])[a];
          approx += b[c] * v[c];
        }
        Vec3 u = volume.ContinuousIndex(x);
        if (clamp) u = volume.ClampToGrid(u);
        const double error = std::abs(volume.SampleIndex(u) - approx) / norm_coeff;
        out.sum_error += error;
        ++out.points;
        if (error > epsilon) ++out.above_epsilon;
        if (error > out.max_error || out.points == 1) {
          out.max_error = error;
          const int zeros = (i == 0) + (j == 0) + (k == 0) + (l == 0);
          const int halves = (2 * i == n) + (2 * j == n) + (2 * k == n) + (2 * l == n);
          if (zeros == 3) {
            out.max_location = MaxLocation::kVertex;
          } else if (zeros == 2) {
            out.max_location = halves == 2 ? MaxLocation::kEdgeMidpoint : MaxLocation::kEdge;
          } else if (zeros == 1) {
            out.max_location = MaxLocation::kFace;
          } else {
            out.max_location = MaxLocation::kInterior;
          }
        }
      }
    }
  }
  return out;
}

// Certified mode's per-tet test as it was before the kernel (edge_marking.cc's TetLatticeMax
// with refine_state.h's SampleInside), verbatim: the reference.
double ReferenceTetLatticeMax(const Volume& volume, const std::array<Vec3, 4>& p,
                              const std::array<double, 4>& v, int n, double norm, double epsilon,
                              bool clamp) {
  const double inv_n = 1.0 / n;
  double worst = 0.0;
  for (int i = 0; i <= n; ++i) {
    for (int j = 0; i + j <= n; ++j) {
      for (int k = 0; i + j + k <= n; ++k) {
        const int l = n - i - j - k;
        if (i == n || j == n || k == n || l == n) continue;
        const double b[4] = {i * inv_n, j * inv_n, k * inv_n, l * inv_n};
        Vec3 x{0, 0, 0};
        double approx = 0.0;
        for (int c = 0; c < 4; ++c) {
          for (int a = 0; a < 3; ++a) x[a] += b[c] * p[c][a];
          approx += b[c] * v[c];
        }
        Vec3 u = volume.ContinuousIndex(x);
        if (clamp) u = volume.ClampToGrid(u);
        const double error = std::abs(volume.SampleIndex(u) - approx) / norm;
        worst = std::max(worst, error);
        if (worst > epsilon) return worst;
      }
    }
  }
  return worst;
}

uint64_t Bits(double x) { return std::bit_cast<uint64_t>(x); }

constexpr VoxelType kTypes[] = {VoxelType::kUint8, VoxelType::kInt16,   VoxelType::kUint16,
                                VoxelType::kInt32, VoxelType::kFloat32, VoxelType::kFloat64};

template <typename T>
void AppendRandom(std::mt19937_64& rng, std::vector<std::byte>& data) {
  T value;
  if constexpr (std::is_floating_point_v<T>) {
    value = static_cast<T>(std::uniform_real_distribution<double>(-1e3, 1e3)(rng));
  } else {
    value = static_cast<T>(std::uniform_int_distribution<int64_t>(
        std::numeric_limits<T>::min(), std::numeric_limits<T>::max())(rng));
  }
  const auto* bytes = reinterpret_cast<const std::byte*>(&value);
  data.insert(data.end(), bytes, bytes + sizeof(T));
}

// A random volume of `type` with random geometry (oblique: a random rotation, mirrored half the
// time), full-range random samples, and with `slab` a random sub-range of the grid.
Volume RandomVolume(std::mt19937_64& rng, VoxelType type, bool oblique, bool slab) {
  std::uniform_int_distribution<int64_t> dim(2, 11);
  std::uniform_real_distribution<double> spacing(0.3, 3.0), origin(-50.0, 50.0);
  GridGeometry g;
  g.dims = {dim(rng), dim(rng), dim(rng)};
  g.spacing = {spacing(rng), spacing(rng), spacing(rng)};
  g.origin = {origin(rng), origin(rng), origin(rng)};
  if (oblique) {
    g.direction = testing::RandomRotation(rng);
    if (rng() % 2 == 1) {
      for (int row = 0; row < 3; ++row) g.direction[3 * row] = -g.direction[3 * row];
    }
  }
  Index3 lo{0, 0, 0}, hi = g.dims;
  if (slab) {
    for (int a = 0; a < 3; ++a) {
      lo[a] = std::uniform_int_distribution<int64_t>(0, g.dims[a] - 2)(rng);
      hi[a] = std::uniform_int_distribution<int64_t>(lo[a] + 2, g.dims[a])(rng);
    }
  }
  std::vector<std::byte> data;
  const int64_t count = (hi[0] - lo[0]) * (hi[1] - lo[1]) * (hi[2] - lo[2]);
  for (int64_t i = 0; i < count; ++i) {
    switch (type) {
      case VoxelType::kUint8:
        AppendRandom<uint8_t>(rng, data);
        break;
      case VoxelType::kInt16:
        AppendRandom<int16_t>(rng, data);
        break;
      case VoxelType::kUint16:
        AppendRandom<uint16_t>(rng, data);
        break;
      case VoxelType::kInt32:
        AppendRandom<int32_t>(rng, data);
        break;
      case VoxelType::kFloat32:
        AppendRandom<float>(rng, data);
        break;
      case VoxelType::kFloat64:
        AppendRandom<double>(rng, data);
        break;
    }
  }
  absl::StatusOr<Volume> v = Volume::Create(g, lo, hi, type, std::move(data));
  EXPECT_TRUE(v.ok()) << v.status();
  return *std::move(v);
}

// A mesh of `tets` random tets (not connected: the lattice does not care) around the volume's
// slab: corners at continuous indices from a cell beyond the slab on every side, so that some
// lattice points need the grid clamp and the slab's cell clamp. Values are sampled at the
// corners (as Refine does) or random, half the time each.
Mesh RandomTets(std::mt19937_64& rng, const Volume& volume, int tets) {
  Mesh mesh;
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const bool sampled = rng() % 2 == 0;
  for (int t = 0; t < tets; ++t) {
    Tet tet;
    for (int c = 0; c < 4; ++c) {
      Vec3 u;
      for (int a = 0; a < 3; ++a) {
        const double lo = static_cast<double>(volume.lo()[a]) - 1.0;
        const double hi = static_cast<double>(volume.hi()[a]);
        u[a] = lo + (hi - lo) * unit(rng);
      }
      // An exact lattice-friendly corner now and then: integer indices put points on cell faces.
      if (rng() % 8 == 0) {
        for (double& x : u) x = std::round(x);
      }
      tet[c] = static_cast<uint32_t>(mesh.points.size());
      const Vec3 p = WorldOfIndex(volume.grid(), u);
      mesh.points.push_back(p);
      mesh.values.push_back(sampled ? volume.SampleIndex(volume.ContinuousIndex(p))
                                    : std::uniform_real_distribution<double>(-2e3, 2e3)(rng));
    }
    mesh.tets.push_back(tet);
  }
  return mesh;
}

void ExpectSame(const TetLattice& got, const TetLattice& want) {
  EXPECT_EQ(Bits(got.max_error), Bits(want.max_error));
  EXPECT_EQ(Bits(got.sum_error), Bits(want.sum_error));
  EXPECT_EQ(got.points, want.points);
  EXPECT_EQ(got.above_epsilon, want.above_epsilon);
  EXPECT_EQ(got.max_location, want.max_location);
}

struct Case {
  VoxelType type;
  bool oblique;
  bool slab;
};

std::vector<Case> EveryCase() {
  std::vector<Case> cases;
  for (VoxelType type : kTypes) {
    for (bool oblique : {false, true}) {
      for (bool slab : {false, true}) cases.push_back({type, oblique, slab});
    }
  }
  return cases;
}

// Calls body(rng, volume, seed) for `seeds` seeds and every case (voxel type, direction, slab),
// the volume drawn from rng first, with the case in the failure trace.
void ForEachVolume(int seeds,
                   const std::function<void(std::mt19937_64&, const Volume&, uint64_t)>& body) {
  for (uint64_t seed : testing::Seeds(seeds)) {
    std::mt19937_64 rng(seed);
    for (const Case& c : EveryCase()) {
      SCOPED_TRACE(::testing::Message() << "seed " << seed << " type " << VoxelTypeName(c.type)
                                        << " oblique " << c.oblique << " slab " << c.slab);
      const Volume volume = RandomVolume(rng, c.type, c.oblique, c.slab);
      body(rng, volume, seed);
    }
  }
}

// Runs body with the portable kernel and, where the CPU has AVX2, with the AVX2 one: both must
// give the reference's bits.
void ForEachKernel(const std::function<void()>& body) {
  const bool was = lattice_internal::LatticeSimd();
  for (bool simd : {false, true}) {
    if (!lattice_internal::SetLatticeSimdForTesting(simd)) continue;
    SCOPED_TRACE(simd ? "AVX2 kernel" : "portable kernel");
    body();
  }
  lattice_internal::SetLatticeSimdForTesting(was);
}

TEST(LatticeKernel, SampleTetLatticeEqualsThePointByPointScanToTheBit) {
  ForEachKernel([] {
    ForEachVolume(6, [](std::mt19937_64& rng, const Volume& volume, uint64_t /*seed*/) {
      const Mesh mesh = RandomTets(rng, volume, 6);
      const double norm = std::uniform_real_distribution<double>(0.5, 3e4)(rng);
      // Epsilon 0 counts every nonzero point above it; the others split the points.
      const double epsilon =
          rng() % 3 == 0 ? 0.0 : std::uniform_real_distribution<double>(0, 0.2)(rng);
      for (int n : {1, 2, 8, 13}) {
        for (bool clamp : {false, true}) {
          for (int64_t t = 0; t < static_cast<int64_t>(mesh.tets.size()); ++t) {
            SCOPED_TRACE(::testing::Message() << "n " << n << " clamp " << clamp << " tet " << t);
            ExpectSame(SampleTetLattice(volume, mesh, t, n, norm, epsilon, clamp),
                       ReferenceTetLattice(volume, mesh, t, n, norm, epsilon, clamp));
          }
        }
      }
    });
  });
}

// SampleLattice sums per block; its maximum, counts and share above epsilon must still be the
// reference's over the same tets (every tet, and a drawn sample of them).
TEST(LatticeKernel, SampleLatticeAgreesWithThePointByPointScan) {
  ForEachKernel([] {
    ForEachVolume(4, [](std::mt19937_64& rng, const Volume& volume, uint64_t seed) {
      const Mesh mesh = RandomTets(rng, volume, 40);
      const double norm = std::uniform_real_distribution<double>(0.5, 3e4)(rng);
      const double epsilon = std::uniform_real_distribution<double>(0, 0.1)(rng);
      const LatticeStats all = SampleLattice(volume, mesh, 8, 0, seed, norm, epsilon, true);
      double max_error = 0.0;
      int64_t points = 0, above = 0;
      for (int64_t t = 0; t < static_cast<int64_t>(mesh.tets.size()); ++t) {
        const TetLattice r = ReferenceTetLattice(volume, mesh, t, 8, norm, epsilon, true);
        max_error = std::max(max_error, r.max_error);
        points += r.points;
        above += r.above_epsilon;
      }
      EXPECT_EQ(Bits(all.max_error), Bits(max_error));
      EXPECT_EQ(all.points_sampled, points);
      EXPECT_EQ(Bits(all.share_above_epsilon),
                Bits(static_cast<double>(above) / static_cast<double>(points)));
      // A sample of 30 draws from the 40 tets, with replacement as SampleLattice draws it: a
      // tet drawn twice counts twice.
      const int64_t draws = 30;
      const LatticeStats sampled = SampleLattice(volume, mesh, 8, draws, seed, norm, epsilon, true);
      std::mt19937_64 draw(seed);
      std::uniform_int_distribution<int64_t> pick(0, static_cast<int64_t>(mesh.tets.size()) - 1);
      max_error = 0.0;
      points = above = 0;
      int repeats = 0;
      std::vector<int64_t> seen;
      for (int64_t d = 0; d < draws; ++d) {
        const int64_t t = pick(draw);
        repeats += std::count(seen.begin(), seen.end(), t) > 0;
        seen.push_back(t);
        const TetLattice r = ReferenceTetLattice(volume, mesh, t, 8, norm, epsilon, true);
        max_error = std::max(max_error, r.max_error);
        points += r.points;
        above += r.above_epsilon;
      }
      EXPECT_GT(repeats, 0);
      EXPECT_EQ(sampled.tets_sampled, draws);
      EXPECT_EQ(Bits(sampled.max_error), Bits(max_error));
      EXPECT_EQ(sampled.points_sampled, points);
      EXPECT_EQ(Bits(sampled.share_above_epsilon),
                Bits(static_cast<double>(above) / static_cast<double>(points)));
    });
  });
}

// With the corners in its points, a passing check's maximum and sum are ScanTetLattice's bits:
// certified mode's final verification reads them instead of sampling the tet again.
TEST(LatticeKernel, PassingCheckGivesTheScansMaximumAndSumToTheBit) {
  ForEachKernel([] {
    ForEachVolume(6, [](std::mt19937_64& rng, const Volume& volume, uint64_t /*seed*/) {
      const Mesh mesh = RandomTets(rng, volume, 6);
      const double norm = std::uniform_real_distribution<double>(0.5, 3e4)(rng);
      int passed = 0;
      for (int n : {1, 2, 8, 13}) {
        const lattice_internal::LatticePoints points(n, /*with_corners=*/true);
        for (const Tet& tet : mesh.tets) {
          const std::array<Vec3, 4> p = {mesh.points[tet[0]], mesh.points[tet[1]],
                                         mesh.points[tet[2]], mesh.points[tet[3]]};
          const std::array<double, 4> v = {mesh.values[tet[0]], mesh.values[tet[1]],
                                           mesh.values[tet[2]], mesh.values[tet[3]]};
          for (double epsilon : {1e300, 0.05, 0.3}) {
            SCOPED_TRACE(::testing::Message() << "n " << n << " epsilon " << epsilon);
            const lattice_internal::LatticeCheck check =
                lattice_internal::CheckLatticeUntil(volume, points, p, v, norm, epsilon);
            const TetLattice scan =
                lattice_internal::ScanTetLattice(volume, points, p, v, norm, epsilon);
            EXPECT_EQ(check.passed, scan.above_epsilon == 0);
            if (!check.passed) continue;
            ++passed;
            EXPECT_EQ(Bits(check.max_error), Bits(scan.max_error));
            EXPECT_EQ(Bits(check.sum_error), Bits(scan.sum_error));
          }
        }
      }
      EXPECT_GT(passed, 0);
    });
  });
}

TEST(LatticeKernel, CertifiedMaximumEqualsThePointByPointScanToTheBit) {
  ForEachKernel([] {
    ForEachVolume(6, [](std::mt19937_64& rng, const Volume& volume, uint64_t /*seed*/) {
      const Mesh mesh = RandomTets(rng, volume, 6);
      const double norm = std::uniform_real_distribution<double>(0.5, 3e4)(rng);
      for (int n : {1, 2, 8, 13}) {
        const lattice_internal::LatticePoints points(n, /*with_corners=*/false);
        for (const Tet& tet : mesh.tets) {
          const std::array<Vec3, 4> p = {mesh.points[tet[0]], mesh.points[tet[1]],
                                         mesh.points[tet[2]], mesh.points[tet[3]]};
          const std::array<double, 4> v = {mesh.values[tet[0]], mesh.values[tet[1]],
                                           mesh.values[tet[2]], mesh.values[tet[3]]};
          // A huge epsilon scans every point; the others stop at different points.
          for (double epsilon : {1e300, 0.0, 0.01, 0.05}) {
            for (bool clamp : {false, true}) {
              SCOPED_TRACE(::testing::Message() << "n " << n << " epsilon " << epsilon);
              EXPECT_EQ(
                  Bits(lattice_internal::CheckLatticeUntil(volume, points, p, v, norm, epsilon)
                           .max_error),
                  Bits(ReferenceTetLatticeMax(volume, p, v, n, norm, epsilon, clamp)));
            }
          }
        }
      }
    });
  });
}

// The batch sampler the edge test uses gives SampleIndex's bits at any index, inside the slab,
// on its cell faces and clamped from outside the grid, for counts that leave every tail length.
TEST(LatticeKernel, SampleIndicesEqualsSampleIndexToTheBit) {
  ForEachKernel([] {
    ForEachVolume(6, [](std::mt19937_64& rng, const Volume& volume, uint64_t /*seed*/) {
      for (int64_t count : {0, 1, 3, 4, 5, 64, 67}) {
        std::vector<double> u[3];
        for (int a = 0; a < 3; ++a) {
          const double lo = static_cast<double>(volume.lo()[a]);
          const double hi = static_cast<double>(volume.hi()[a] - 1);
          std::uniform_real_distribution<double> inside(lo, hi);
          for (int64_t i = 0; i < count; ++i) {
            // Mostly inside the slab; some on a sample plane, some outside the grid.
            const int64_t kind = static_cast<int64_t>(rng() % 8);
            u[a].push_back(kind == 0   ? std::floor(inside(rng))
                           : kind == 1 ? inside(rng) - 3.0 * hi
                           : kind == 2 ? inside(rng) + 3.0 * hi
                                       : inside(rng));
          }
        }
        std::vector<double> got(static_cast<size_t>(count));
        lattice_internal::SampleIndices(volume, u[0].data(), u[1].data(), u[2].data(), count,
                                        got.data());
        for (int64_t i = 0; i < count; ++i) {
          EXPECT_EQ(Bits(got[i]), Bits(volume.SampleIndex({u[0][i], u[1][i], u[2][i]})))
              << "count " << count << " point " << i;
        }
      }
    });
  });
}

// The AVX2 kernel runs wherever the CPU has it: a build that lost it would be slower, not wrong,
// and nothing else would notice.
TEST(LatticeKernel, UsesAvx2WhereTheCpuHasIt) {
#if defined(__x86_64__)
  EXPECT_EQ(lattice_internal::LatticeSimd(), __builtin_cpu_supports("avx2") != 0);
#else
  EXPECT_FALSE(lattice_internal::LatticeSimd());
#endif
}

// The table keeps the scan order and the reference's point count, with and without corners.
TEST(LatticeKernel, PointTableHoldsTheLatticeInScanOrder) {
  for (int n : {1, 2, 8, 13, 64}) {
    const lattice_internal::LatticePoints all(n, true), inner(n, false);
    const int64_t count = int64_t{n + 1} * (n + 2) * (n + 3) / 6;
    ASSERT_EQ(all.size(), count);
    ASSERT_EQ(inner.size(), count - 4);
    const double inv_n = 1.0 / n;
    int64_t a = 0, b = 0;
    for (int i = 0; i <= n; ++i) {
      for (int j = 0; i + j <= n; ++j) {
        for (int k = 0; i + j + k <= n; ++k) {
          const int l = n - i - j - k;
          const double want[4] = {i * inv_n, j * inv_n, k * inv_n, l * inv_n};
          const bool corner = i == n || j == n || k == n || l == n;
          for (int c = 0; c < 4; ++c) {
            EXPECT_EQ(Bits(all.b(c)[a]), Bits(want[c])) << "n " << n << " point " << a;
            if (!corner) {
              EXPECT_EQ(Bits(inner.b(c)[b]), Bits(want[c])) << "n " << n;
            }
          }
          EXPECT_EQ(all.location(a) == MaxLocation::kVertex, corner) << "n " << n << " " << a;
          ++a;
          b += !corner;
        }
      }
    }
  }
}

}  // namespace
}  // namespace tetrefine
