// Refinement at the API level on the ripple workload (bench/support/ripple_workload.h):
//   BM_Iteration    Refine with max_iterations = 1: validation, vertex sampling, one iteration
//                   (edge table, edge marking, subdivision) and the edge pass that finds the
//                   returned mesh's error.
//   BM_EdgeMarking  Refine with max_iterations = 0: validation, vertex sampling and one edge
//                   pass (edge table and marking), no subdivision.
// Sizes 10k, 100k, 1M and 10M tets; one thread and all cores.
// Run: build/bench/iteration_bench --benchmark_counters_tabular=true
#include <benchmark/benchmark.h>
#include <time.h>

#include <cstdio>
#include <cstdlib>
#include <map>
#include <thread>

#include "bench/support/ripple_workload.h"
#include "core/refine.h"

namespace tetrefine::bench {
namespace {

const RippleWorkload& Workload(int cells) {
  static auto* cache = [] {
    // Untimed warm-up: the first Refine of a process starts the thread pool and builds the
    // subdivision table, which would otherwise land on whichever benchmark runs first.
    const RippleWorkload tiny = MakeRippleWorkload(2);
    RefineOptions o;
    o.lattice_n = 0;
    (void)Refine(tiny.volume, tiny.mesh, o);
    return new std::map<int, RippleWorkload>();
  }();
  auto it = cache->find(cells);
  if (it == cache->end()) it = cache->emplace(cells, MakeRippleWorkload(cells)).first;
  return it->second;
}

// CPU time of the whole process (every thread), seconds.
double ProcessCpuSeconds() {
  timespec t{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

void RunRefine(benchmark::State& state, int max_iterations) {
  const RippleWorkload& w = Workload(static_cast<int>(state.range(0)));
  const int threads = static_cast<int>(state.range(1));
  RefineOptions o;
  o.epsilon = kRippleEpsilon;
  o.max_iterations = max_iterations;
  o.lattice_n = 0;
  o.threads = threads;
  // The paper's scheme: docs/results/benchmarks.md has measured it since the first version, so
  // its figures stay comparable; core_bench puts the schemes side by side.
  o.scheme = RefineScheme::kPaper;
  int64_t out = 0;
  double cpu = 0.0;
  for (auto _ : state) {
    const double cpu_start = ProcessCpuSeconds();
    absl::StatusOr<RefineResult> r = Refine(w.volume, w.mesh, o);
    cpu += ProcessCpuSeconds() - cpu_start;
    if (!r.ok()) {
      state.SkipWithError(std::string(r.status().message()).c_str());
      return;
    }
    out = static_cast<int64_t>(r->mesh.tets.size());
    benchmark::DoNotOptimize(r);
    // Freeing the result (unmapping ~100 MB at 1M tets) is the caller's cost, not the call's.
    state.PauseTiming();
    r = absl::StatusOr<RefineResult>();
    state.ResumeTiming();
  }
  const double in = static_cast<double>(w.mesh.tets.size());
  state.counters["threads"] = threads;
  state.counters["tets_in"] = in;
  state.counters["tets_out"] = static_cast<double>(out);
  using C = benchmark::Counter;
  state.counters["in_tets_per_s"] = C(in, C::kIsIterationInvariantRate);
  state.counters["out_tets_per_s"] = C(static_cast<double>(out), C::kIsIterationInvariantRate);
  state.counters["out_tets_per_s_per_core"] =
      C(static_cast<double>(out) / threads, C::kIsIterationInvariantRate);
  // Output tets per CPU-second of all threads: per-core throughput that other work on the machine
  // disturbs less than the wall-clock rates.
  state.counters["cpu_s"] = cpu / static_cast<double>(state.iterations());
  state.counters["out_tets_per_cpu_s"] =
      static_cast<double>(out) * static_cast<double>(state.iterations()) / cpu;
}

void BM_Iteration(benchmark::State& state) { RunRefine(state, 1); }
void BM_EdgeMarking(benchmark::State& state) { RunRefine(state, 0); }

// 13, 27, 58 and 126 cells per axis: 11k, 98k, 976k and 10.0M tets.
void Sizes(benchmark::internal::Benchmark* b) {
  const int cores = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  for (int cells : {13, 27, 58, 126}) {
    b->Args({cells, 1});
    if (cores > 1) b->Args({cells, cores});
  }
}
BENCHMARK(BM_Iteration)
    ->Apply(Sizes)
    ->ArgNames({"cells", "threads"})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK(BM_EdgeMarking)
    ->Apply(Sizes)
    ->ArgNames({"cells", "threads"})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace
}  // namespace tetrefine::bench

BENCHMARK_MAIN();
