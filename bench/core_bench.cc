// One refinement iteration of a structured mesh of about a million tets, at 1 and 2 threads.
// Run: build/bench/core_bench --benchmark_counters_tabular=true
// iter_out_per_s: output tets per second of the iteration itself (edge table, edge errors,
// subdivision: IterationStats::seconds). call_out_per_s: of the whole Refine call, which adds
// the one-off input validation and sampling and the final edge-error pass, and with lattice = 1
// the default verification (order 8 on a sample of 200 000 tets). scheme: 0 the paper's, 1
// longest-edge (the default), so that the two are measured side by side in one run.
// BM_Certified: the same with certified mode's per-tet lattice.
#include <benchmark/benchmark.h>
#include <tbb/task_arena.h>

#include <cmath>
#include <map>
#include <vector>

#include "core/mesh_validation.h"
#include "core/quality.h"
#include "core/refine.h"
#include "tests/support/geometry.h"

namespace tetrefine {
namespace {

struct Fixture {
  Volume volume;
  Mesh mesh;
};

const Fixture& Setup(int cells) {
  static std::map<int, Fixture>* cache = new std::map<int, Fixture>();
  auto it = cache->find(cells);
  if (it != cache->end()) return it->second;
  GridGeometry g;
  g.dims = {128, 128, 64};
  g.spacing = {1.0, 1.0, 2.0};
  // Ripples of a few voxels: about a third of the edges split in the first iteration.
  Volume volume = testing::AnalyticVolume(g, [](const Vec3& p) {
    return 100.0 * std::sin(p[0] * 0.35) * std::cos(p[1] * 0.29) * std::sin(p[2] * 0.11);
  });
  Mesh mesh = testing::FiveTetMesh({0, 0, 0}, {127, 127, 126}, {cells, cells, cells});
  return cache->emplace(cells, Fixture{std::move(volume), std::move(mesh)}).first->second;
}

void BM_OneIteration(benchmark::State& state) {
  const Fixture& f = Setup(static_cast<int>(state.range(0)));
  RefineOptions o;
  o.epsilon = state.range(2) / 1000.0;
  o.max_iterations = 1;
  o.threads = static_cast<int>(state.range(1));
  o.scheme = state.range(3) == 0 ? RefineScheme::kPaper : RefineScheme::kLongestEdge;
  if (state.range(4) == 0) o.lattice_n = 0;  // else the default verification
  int64_t out = 0;
  double iteration_seconds = 0.0;
  for (auto _ : state) {
    auto r = Refine(f.volume, f.mesh, o);
    out = static_cast<int64_t>(r->mesh.tets.size());
    iteration_seconds += r->iterations.at(0).seconds;
    benchmark::DoNotOptimize(r);
  }
  state.counters["iter_out_per_s"] =
      static_cast<double>(out) * static_cast<double>(state.iterations()) / iteration_seconds;
  state.counters["tets_in"] = static_cast<double>(f.mesh.tets.size());
  state.counters["tets_out"] = static_cast<double>(out);
  state.counters["call_out_per_s"] =
      benchmark::Counter(static_cast<double>(out), benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_OneIteration)
    ->ArgNames({"cells", "threads", "eps_x1000", "scheme", "lattice"})
    ->Args({20, 1, 50, 0, 0})
    ->Args({20, 1, 50, 1, 0})
    ->Args({58, 1, 50, 0, 0})
    ->Args({58, 1, 50, 1, 0})
    ->Args({58, 1, 50, 0, 1})
    ->Args({58, 1, 50, 1, 1})
    ->Args({58, 2, 50, 0, 0})
    ->Args({58, 2, 50, 1, 0})
    ->Args({58, 1, 10, 0, 0})
    ->Args({58, 1, 10, 1, 0})
    ->Args({58, 2, 10, 0, 0})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// A whole call as a user makes it: a coarse mesh refined until every edge passes epsilon, one
// thread, the default scheme and its default verification (lattice order 8 on a sample of
// 200 000 tets). Unlike BM_OneIteration, whose output is barely larger than its input, the input
// validation is small here and the output comes from several iterations. call_out_per_s as
// above; iterations and converged (1 or 0) say what the call did; iteration_share is the part of
// the call spent in its iterations (IterationStats::seconds) and last_iteration_s the last one's.
// Measured 2026-11-24, one thread: 40,000 -> 3,878,176 tets in 4 iterations, 5.25 s (0.74 M
// output tets/s), of which 1.97 s is the last iteration, which adds 36,296 tets to 3.84 M: a
// late iteration costs what its whole input costs (edge table, tet edges, closure passes,
// copies), not what it changes. At epsilon 0.01 (6 iterations, 10.97 M tets): 0.47 M/s.
// With huge pages for the edge table and the subdivision's arrays (2026-11-24, side by side
// with the commit before on a slower day): 6.35-7.17 s -> 4.61-4.77 s. With the edge table and
// the tet edges updated from the iteration before (core/edge_table.h UpdateEdgeTable,
// UpdateTetEdges), 3.56-4.39 s -> 3.31-3.47 s (1.0-1.17 M/s): here the last iteration follows
// one that made most of the tets, so it gains little; runs with several late iterations gain
// more (the T1 brain `--block 4` mesh at eps 0.05, 8 iterations: whole CLI run 9.1-11.9 s ->
// 5.8-8.5 s, one thread).
void BM_ToConvergence(benchmark::State& state) {
  const Fixture& f = Setup(static_cast<int>(state.range(0)));
  RefineOptions o;
  o.epsilon = state.range(1) / 1000.0;
  o.threads = 1;
  int64_t out = 0;
  double iterations = 0.0, converged = 0.0, iteration_share = 0.0, last_iteration_seconds = 0.0;
  for (auto _ : state) {
    auto r = Refine(f.volume, f.mesh, o);
    out = static_cast<int64_t>(r->mesh.tets.size());
    iterations = static_cast<double>(r->iterations.size());
    converged = r->stop_reason == StopReason::kConverged ? 1.0 : 0.0;
    double in_iterations = 0.0;
    for (const IterationStats& it : r->iterations) in_iterations += it.seconds;
    iteration_share = in_iterations / r->seconds;
    last_iteration_seconds = r->iterations.empty() ? 0.0 : r->iterations.back().seconds;
    benchmark::DoNotOptimize(r);
  }
  state.counters["iteration_share"] = iteration_share;
  state.counters["last_iteration_s"] = last_iteration_seconds;
  state.counters["tets_in"] = static_cast<double>(f.mesh.tets.size());
  state.counters["tets_out"] = static_cast<double>(out);
  state.counters["iterations"] = iterations;
  state.counters["converged"] = converged;
  state.counters["call_out_per_s"] =
      benchmark::Counter(static_cast<double>(out), benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_ToConvergence)
    ->ArgNames({"cells", "eps_x1000"})
    ->Args({20, 20})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// Certified mode (RefineOptions::certify): one iteration that also samples every tet's lattice
// (order 8, 161 points without the corners), then the check of the new tets, one thread.
// call_out_per_s as above.
void BM_Certified(benchmark::State& state) {
  const Fixture& f = Setup(static_cast<int>(state.range(0)));
  RefineOptions o;
  o.epsilon = state.range(1) / 1000.0;
  o.max_iterations = 1;
  o.threads = 1;
  o.certify = true;
  o.lattice_n = 8;
  int64_t out = 0;
  for (auto _ : state) {
    auto r = Refine(f.volume, f.mesh, o);
    out = static_cast<int64_t>(r->mesh.tets.size());
    benchmark::DoNotOptimize(r);
  }
  state.counters["tets_in"] = static_cast<double>(f.mesh.tets.size());
  state.counters["tets_out"] = static_cast<double>(out);
  state.counters["call_out_per_s"] =
      benchmark::Counter(static_cast<double>(out), benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_Certified)
    ->ArgNames({"cells", "eps_x1000"})
    ->Args({30, 50})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// QualityReference (the default floor of the longest-edge guard) over the ~1M-tet mesh, one
// thread: a mean ratio of every tet with its corners sorted, the cube root only for the tets that
// may be the worst. jitter 1: every point moved by up to a tenth of a cell (a fixed sequence), so
// that the tets are not congruent: on the structured mesh four tets in five tie with the worst in
// shape and still take the cube root.
void BM_QualityReference(benchmark::State& state) {
  const Fixture& f = Setup(static_cast<int>(state.range(0)));
  std::vector<Vec3> points = f.mesh.points;
  if (state.range(1) != 0) {
    const double step = 127.0 / static_cast<double>(state.range(0));
    uint64_t x = 88172645463325252ull;
    for (Vec3& p : points) {
      for (double& c : p) {
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        c += (static_cast<double>(x % 2001) / 1000.0 - 1.0) * 0.1 * step;
      }
    }
  }
  tbb::task_arena arena(1);
  for (auto _ : state) {
    arena.execute([&] { benchmark::DoNotOptimize(QualityReference(points, f.mesh.tets)); });
  }
  state.counters["tets_per_s"] = benchmark::Counter(static_cast<double>(f.mesh.tets.size()),
                                                    benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_QualityReference)
    ->ArgNames({"cells", "jitter"})
    ->Args({58, 0})
    ->Args({58, 1})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// Input validation of the same mesh at 1 and 2 threads, in its parts: 0 the face check alone,
// 1 the conformity check alone (hanging nodes, closed boundary; on the face check's boundary
// faces), 2 both (CheckConformity: the face check listing the boundary, then the conformity
// check), 3 all of ValidateMesh (points, tets, orientation, box, faces, conformity).
void BM_Validation(benchmark::State& state) {
  const Fixture& f = Setup(static_cast<int>(state.range(0)));
  const int part = static_cast<int>(state.range(2));
  std::vector<BoundaryFace> boundary;
  if (!CheckFaces(f.mesh.points, f.mesh.tets, &boundary).ok()) state.SkipWithError("faces");
  tbb::task_arena arena(static_cast<int>(state.range(1)));
  for (auto _ : state) {
    absl::Status s;
    arena.execute([&] {
      if (part == 0) {
        s = CheckFaces(f.mesh.points, f.mesh.tets);
      } else if (part == 1) {
        s = CheckBoundaryConformity(f.mesh.points, f.mesh.tets, boundary);
      } else if (part == 2) {
        s = CheckConformity(f.mesh.points, f.mesh.tets);
      } else {
        std::vector<Tet> tets;
        int64_t reoriented = 0;
        s = ValidateMesh(f.mesh, f.volume, OutsidePolicy::kReject, OrientationPolicy::kReject,
                         &tets, &reoriented);
      }
    });
    if (!s.ok()) state.SkipWithError(std::string(s.message()).c_str());
  }
  state.counters["tets_in"] = static_cast<double>(f.mesh.tets.size());
  state.counters["boundary_faces"] = static_cast<double>(boundary.size());
}
BENCHMARK(BM_Validation)
    ->ArgNames({"cells", "threads", "part"})
    ->ArgsProduct({{60}, {1, 2}, {0, 1, 2, 3}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// The conformity check where its work is largest relative to the face check's: 0 250 000
// separate tets (every face is boundary), 1 a 40^3-cell FiveTetMesh graded so its cells span a
// factor 2^13 in size (the hash grid's levels). Parts as in BM_Validation, 1 thread.
const Mesh& HardMesh(int kind) {
  static std::map<int, Mesh>* cache = new std::map<int, Mesh>();
  auto it = cache->find(kind);
  if (it != cache->end()) return it->second;
  Mesh m;
  if (kind == 0) {
    for (int i = 0; i < 250'000; ++i) {
      const Vec3 o = {2.0 * (i % 100), 2.0 * (i / 100 % 50), 2.0 * (i / 5000)};
      const auto v = static_cast<uint32_t>(m.points.size());
      m.points.push_back(o);
      m.points.push_back({o[0] + 1, o[1], o[2]});
      m.points.push_back({o[0], o[1] + 1, o[2]});
      m.points.push_back({o[0], o[1], o[2] + 1});
      m.tets.push_back({v, v + 1, v + 2, v + 3});
    }
  } else {
    m = testing::FiveTetMesh({0, 0, 0}, {40, 40, 40}, {40, 40, 40});
    for (Vec3& p : m.points) {
      for (double& x : p) x = std::exp2(x / 3.0);
    }
  }
  return cache->emplace(kind, std::move(m)).first->second;
}

void BM_ValidationHard(benchmark::State& state) {
  const Mesh& m = HardMesh(static_cast<int>(state.range(0)));
  const int part = static_cast<int>(state.range(1));
  std::vector<BoundaryFace> boundary;
  if (!CheckFaces(m.points, m.tets, &boundary).ok()) state.SkipWithError("faces");
  tbb::task_arena arena(1);
  for (auto _ : state) {
    absl::Status s;
    arena.execute([&] {
      if (part == 0) {
        s = CheckFaces(m.points, m.tets);
      } else if (part == 1) {
        s = CheckBoundaryConformity(m.points, m.tets, boundary);
      } else {
        s = CheckConformity(m.points, m.tets);
      }
    });
    if (!s.ok()) state.SkipWithError(std::string(s.message()).c_str());
  }
  state.counters["tets_in"] = static_cast<double>(m.tets.size());
  state.counters["boundary_faces"] = static_cast<double>(boundary.size());
}
BENCHMARK(BM_ValidationHard)
    ->ArgNames({"kind", "part"})
    ->ArgsProduct({{0, 1}, {0, 1, 2}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace
}  // namespace tetrefine

BENCHMARK_MAIN();
