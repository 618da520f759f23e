// Subdividing one tet by configuration: the key (face and octahedron diagonals from geometry),
// the table lookup, the Steiner point when there is one, and writing the children as global
// vertex ids. Random well-shaped tets, each configuration's canonical split pattern.
// Run: build/bench/subdivision_bench
#include <benchmark/benchmark.h>

#include <array>
#include <random>
#include <vector>

#include "core/configuration.h"
#include "core/mesh.h"
#include "core/quality.h"
#include "core/subdivision_table.h"
#include "core/tet_topology.h"

namespace tetrefine::bench {
namespace {

struct LocalTet {
  std::array<Vec3, 10> points;      // corners and edge midpoints (tet_topology.h numbering)
  std::array<uint32_t, 11> global;  // their mesh vertex ids, and the Steiner point's
};

std::vector<LocalTet> RandomTets(int count) {
  std::mt19937_64 rng(20261122);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::vector<LocalTet> tets;
  uint32_t next_id = 0;
  while (static_cast<int>(tets.size()) < count) {
    std::array<Vec3, 4> c;
    for (Vec3& p : c) p = {u(rng), u(rng), u(rng)};
    if (MeanRatio(c[0], c[1], c[2], c[3]) < 0.05) continue;
    if (SignedVolume6(c[0], c[1], c[2], c[3]) < 0) std::swap(c[2], c[3]);
    LocalTet t;
    for (int i = 0; i < 4; ++i) t.points[i] = c[i];
    for (int e = 0; e < 6; ++e) {
      for (int a = 0; a < 3; ++a) {
        t.points[4 + e][a] = 0.5 * (c[kTetEdges[e][0]][a] + c[kTetEdges[e][1]][a]);
      }
    }
    for (uint32_t& g : t.global) g = next_id++;
    tets.push_back(t);
  }
  return tets;
}

void BM_Subdivide(benchmark::State& state) {
  const auto configuration = static_cast<Configuration>(state.range(0));
  const uint32_t pattern = CanonicalPattern(configuration);
  const std::vector<LocalTet> tets = RandomTets(4096);
  const auto& table = SubdivisionTable();
  std::vector<Tet> children(tets.size() * 11);
  std::vector<Vec3> steiner_points(tets.size());
  int64_t written = 0;
  for (auto _ : state) {
    size_t out = 0, steiners = 0;
    for (const LocalTet& t : tets) {
      const SubdivisionEntry& e = table[SubdivisionKey(pattern, t.points)];
      if (e.steiner) {
        std::array<Vec3, 6> prism;
        for (int i = 0; i < 6; ++i) prism[i] = t.points[e.steiner_of[i]];
        steiner_points[steiners++] = SteinerPoint(prism);
      }
      for (int c = 0; c < e.tet_count; ++c) {
        const auto& l = e.tets[c];
        children[out++] = {t.global[l[0]], t.global[l[1]], t.global[l[2]], t.global[l[3]]};
      }
    }
    written = static_cast<int64_t>(out);
    benchmark::DoNotOptimize(children.data());
    benchmark::DoNotOptimize(steiner_points.data());
  }
  state.SetLabel(std::string(ConfigurationName(configuration)));
  state.SetItemsProcessed(state.iterations() * static_cast<int64_t>(tets.size()));
  state.counters["children_per_tet"] =
      static_cast<double>(written) / static_cast<double>(tets.size());
  state.counters["children_per_s"] = benchmark::Counter(
      static_cast<double>(written), benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_Subdivide)->DenseRange(0, kNumConfigurations - 1);

}  // namespace
}  // namespace tetrefine::bench

BENCHMARK_MAIN();
