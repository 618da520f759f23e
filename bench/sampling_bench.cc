// Trilinear sampling (Volume::Sample) at random points of a 128 x 128 x 64 volume, by voxel type,
// and the lattice verification (SampleLattice at the default order 8 over 200 000 tets of a
// 1M-tet mesh, one thread), whose inner loop is such samples.
// Run: build/bench/sampling_bench
#include <benchmark/benchmark.h>

#include <random>
#include <vector>

#include "bench/support/ripple_workload.h"
#include "core/lattice.h"
#include "core/volume.h"
#include "tbb/task_arena.h"

namespace tetrefine::bench {
namespace {

void BM_Sample(benchmark::State& state, VoxelType type) {
  const Volume volume = MakeRippleWorkload(1, type).volume;
  const GridGeometry& g = volume.grid();
  std::mt19937_64 rng(20261122);
  std::vector<Vec3> points(1 << 16);
  for (Vec3& p : points) {
    for (int a = 0; a < 3; ++a) {
      std::uniform_real_distribution<double> u(
          g.origin[a], g.origin[a] + static_cast<double>(g.dims[a] - 1) * g.spacing[a]);
      p[a] = u(rng);
    }
  }
  for (auto _ : state) {
    double sum = 0.0;
    for (const Vec3& p : points) sum += volume.Sample(p);
    benchmark::DoNotOptimize(sum);
  }
  state.SetItemsProcessed(state.iterations() * static_cast<int64_t>(points.size()));
  state.counters["samples_per_s"] = benchmark::Counter(
      static_cast<double>(points.size()), benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK_CAPTURE(BM_Sample, int16, VoxelType::kInt16);
BENCHMARK_CAPTURE(BM_Sample, float64, VoxelType::kFloat64);

// points_per_s: lattice points (165 per tet) per second. clamp: OutsidePolicy::kClamp's flag.
void BM_Lattice(benchmark::State& state, VoxelType type) {
  RippleWorkload w = MakeRippleWorkload(58, type);
  w.mesh.values.resize(w.mesh.points.size());
  for (size_t i = 0; i < w.mesh.points.size(); ++i) {
    w.mesh.values[i] = w.volume.Sample(w.mesh.points[i]);
  }
  const auto range = w.volume.ValueRange();
  tbb::task_arena one(1);
  int64_t points = 0;
  for (auto _ : state) {
    one.execute([&] {
      const LatticeStats s = SampleLattice(w.volume, w.mesh, 8, 200'000, 1, range[1] - range[0],
                                           kRippleEpsilon, /*clamp=*/true);
      points = s.points_sampled;
      benchmark::DoNotOptimize(s);
    });
  }
  state.counters["points_per_s"] = benchmark::Counter(
      static_cast<double>(points), benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK_CAPTURE(BM_Lattice, int16, VoxelType::kInt16)
    ->ArgName("clamp")
    ->Arg(0)
    ->Arg(1)
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_Lattice, float64, VoxelType::kFloat64)
    ->ArgName("clamp")
    ->Arg(0)
    ->Arg(1)
    ->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace tetrefine::bench

BENCHMARK_MAIN();
