// Trilinear sampling (Volume::Sample) at random points of a 128 x 128 x 64 volume, by voxel type.
// Run: build/bench/sampling_bench
#include <benchmark/benchmark.h>

#include <random>
#include <vector>

#include "bench/support/ripple_workload.h"
#include "core/volume.h"

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

}  // namespace
}  // namespace tetrefine::bench

BENCHMARK_MAIN();
