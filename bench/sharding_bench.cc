// Sharded refinement (client/sharding) over replicas on loopback TCP in this process, against one
// unsharded call with the whole volume. The ripple workload with 80 cells per axis: 2.56 M input
// tets, two iterations at epsilon 0.05, 4.8 M output tets. Each replica refines with one thread,
// as a one-core pod would; on a 2-core machine K = 2 can use both cores and K = 4 oversubscribes
// them.
// Counters: output tets per second, voxel bytes sent per part (largest and summed) and their
// share of the whole volume, and the client's own work per run (splitting, merging).
// Run: build/bench/sharding_bench --benchmark_counters_tabular=true
#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <memory>
#include <string>
#include <vector>

#include "bench/support/ripple_workload.h"
#include "client/refine_client.h"
#include "client/sharding/sharded_refine.h"
#include "grpcpp/grpcpp.h"
#include "server/refiner_service.h"
#include "server/server_setup.h"
#include "spdlog/spdlog.h"

namespace tetrefine::bench {
namespace {

constexpr int kReplicas = 4;
constexpr int kCells = 80;
constexpr int kIterations = 2;
constexpr double kEpsilon = 0.05;

struct Replica {
  std::unique_ptr<server::RefinerService> service;
  std::unique_ptr<grpc::Server> server;
};

struct Cluster {
  std::vector<Replica> replicas;
  std::vector<std::shared_ptr<grpc::Channel>> channels;
  RippleWorkload work = MakeRippleWorkload(kCells);
};

const Cluster* StartCluster() {
  static Cluster* cluster = [] {
    spdlog::set_level(spdlog::level::warn);  // no log line per call in the figures
    auto* c = new Cluster();
    server::InitGrpcFeatures();
    server::ServiceConfig config;
    config.refine_threads = 1;
    for (int i = 0; i < kReplicas; ++i) {
      Replica r;
      r.service = std::make_unique<server::RefinerService>(config);
      grpc::ServerBuilder builder;
      int port = 0;
      builder.AddListeningPort("127.0.0.1:0", grpc::InsecureServerCredentials(), &port);
      r.server = server::StartServer(config, r.service.get(), &builder);
      if (r.server == nullptr || port == 0) return static_cast<Cluster*>(nullptr);
      auto channel = grpc::CreateChannel("127.0.0.1:" + std::to_string(port),
                                         grpc::InsecureChannelCredentials());
      channel->WaitForConnected(std::chrono::system_clock::now() + std::chrono::seconds(10));
      c->channels.push_back(channel);
      c->replicas.push_back(std::move(r));
    }
    return c;
  }();
  return cluster;
}

client::RefineRequestOptions Options() {
  client::RefineRequestOptions o;
  o.refine.epsilon = kEpsilon;
  o.refine.max_iterations = kIterations;
  o.refine.lattice_n = 0;
  return o;
}

void BM_Unsharded(benchmark::State& state) {
  const Cluster* c = StartCluster();
  if (c == nullptr) return state.SkipWithError("the loopback replicas did not start");
  int64_t tets = 0;
  for (auto _ : state) {
    auto r = client::RefineViaService(c->channels[0], c->work.volume, c->work.mesh, Options());
    if (!r.ok()) return state.SkipWithError(r.status().ToString().c_str());
    tets = static_cast<int64_t>(r->result.mesh.tets.size());
  }
  const double whole = static_cast<double>(c->work.volume.data().size());
  state.counters["out_tets"] = static_cast<double>(tets);
  state.counters["out_tets/s"] =
      benchmark::Counter(static_cast<double>(tets), benchmark::Counter::kIsIterationInvariantRate);
  state.counters["part_MB_max"] = whole / 1e6;
  state.counters["parts_MB_sum"] = whole / 1e6;
  state.counters["max_share"] = 1.0;
}

void BM_Sharded(benchmark::State& state) {
  const Cluster* c = StartCluster();
  if (c == nullptr) return state.SkipWithError("the loopback replicas did not start");
  sharding::ShardOptions shard;
  shard.shards = static_cast<int>(state.range(0));
  int64_t tets = 0, largest = 0, sum = 0;
  double split = 0.0, merge = 0.0;
  for (auto _ : state) {
    auto r = sharding::ShardedRefine(c->channels, c->work.volume, c->work.mesh, Options(), shard);
    if (!r.ok()) return state.SkipWithError(r.status().ToString().c_str());
    tets = static_cast<int64_t>(r->reply.result.mesh.tets.size());
    split += r->split_seconds;
    merge += r->merge_seconds;
    largest = sum = 0;
    for (const sharding::ShardReport& s : r->shards) {
      largest = std::max(largest, s.volume_bytes);
      sum += s.volume_bytes;
    }
  }
  const double whole = static_cast<double>(c->work.volume.data().size());
  state.counters["out_tets"] = static_cast<double>(tets);
  state.counters["out_tets/s"] =
      benchmark::Counter(static_cast<double>(tets), benchmark::Counter::kIsIterationInvariantRate);
  state.counters["part_MB_max"] = static_cast<double>(largest) / 1e6;
  state.counters["parts_MB_sum"] = static_cast<double>(sum) / 1e6;
  state.counters["max_share"] = static_cast<double>(largest) / whole;
  state.counters["split_s"] = benchmark::Counter(split, benchmark::Counter::kAvgIterations);
  state.counters["merge_s"] = benchmark::Counter(merge, benchmark::Counter::kAvgIterations);
}

BENCHMARK(BM_Unsharded)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(3);
BENCHMARK(BM_Sharded)
    ->ArgName("shards")
    ->Arg(1)
    ->Arg(2)
    ->Arg(4)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->Iterations(3);

}  // namespace
}  // namespace tetrefine::bench

BENCHMARK_MAIN();
