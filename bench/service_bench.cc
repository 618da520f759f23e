// The gRPC service over loopback TCP against core Refine in the same process, on the same work
// (the ~1M-tet ripple workload, one iteration, all cores on both sides). Each benchmark
// iteration runs both and reports their times and the ratio service / core.
// Run: build/bench/service_bench --benchmark_counters_tabular=true
#include <benchmark/benchmark.h>

#include <chrono>
#include <memory>
#include <string>

#include "bench/support/ripple_workload.h"
#include "client/refine_client.h"
#include "core/refine.h"
#include "grpcpp/grpcpp.h"
#include "server/refiner_service.h"
#include "server/server_setup.h"

namespace tetrefine::bench {
namespace {

using Clock = std::chrono::steady_clock;

double Since(Clock::time_point t) {
  return std::chrono::duration<double>(Clock::now() - t).count();
}

// A real server on 127.0.0.1, kept for the whole run.
struct Loopback {
  std::unique_ptr<server::RefinerService> service;
  std::unique_ptr<grpc::Server> server;
  std::shared_ptr<grpc::Channel> channel;
};

const Loopback* StartLoopback() {
  static Loopback* loopback = [] {
    auto* l = new Loopback();
    server::InitGrpcFeatures();
    server::ServiceConfig config;  // refine_threads = 0: all cores, as core below
    l->service = std::make_unique<server::RefinerService>(config);
    grpc::ServerBuilder builder;
    int port = 0;
    builder.AddListeningPort("127.0.0.1:0", grpc::InsecureServerCredentials(), &port);
    l->server = server::StartServer(config, l->service.get(), &builder);
    if (l->server == nullptr || port == 0) return static_cast<Loopback*>(nullptr);
    l->channel = grpc::CreateChannel("127.0.0.1:" + std::to_string(port),
                                     grpc::InsecureChannelCredentials());
    // Connected up front, so the first timed call does not pay for the handshake.
    l->channel->WaitForConnected(std::chrono::system_clock::now() + std::chrono::seconds(10));
    return l;
  }();
  return loopback;
}

void BM_ServiceVsCore(benchmark::State& state) {
  const RippleWorkload w = MakeRippleWorkload(static_cast<int>(state.range(0)));
  const Loopback* loopback = StartLoopback();
  if (loopback == nullptr) {
    state.SkipWithError("the loopback server did not start");
    return;
  }
  RefineOptions o;
  o.epsilon = kRippleEpsilon;
  o.max_iterations = 1;
  o.lattice_n = 0;
  const client::RefineRequestOptions request = wire::RequestOptionsFromCore(o);
  client::CallOptions call;
  call.wait_for_ready = true;
  // Untimed warm-up of both paths (thread pool, subdivision table, the connection).
  call.deadline = std::chrono::system_clock::now() + std::chrono::minutes(5);
  (void)Refine(w.volume, w.mesh, o);
  (void)client::RefineViaService(loopback->channel, w.volume, w.mesh, request, {}, call);
  double core_s = 0.0, service_s = 0.0, server_s = 0.0, input_s = 0.0, refine_s = 0.0;
  int64_t out = 0;
  for (auto _ : state) {
    auto t = Clock::now();
    absl::StatusOr<RefineResult> core = Refine(w.volume, w.mesh, o);
    core_s += Since(t);
    t = Clock::now();
    call.deadline = std::chrono::system_clock::now() + std::chrono::minutes(5);
    absl::StatusOr<client::ClientResult> remote =
        client::RefineViaService(loopback->channel, w.volume, w.mesh, request, {}, call);
    service_s += Since(t);
    if (!core.ok() || !remote.ok()) {
      state.SkipWithError(
          std::string((core.ok() ? remote.status() : core.status()).message()).c_str());
      return;
    }
    if (remote->result.mesh.tets.size() != core->mesh.tets.size()) {
      state.SkipWithError("service and core results differ");
      return;
    }
    server_s += remote->service.total_seconds;
    input_s += remote->service.input_seconds;
    refine_s += remote->result.seconds;
    out = static_cast<int64_t>(core->mesh.tets.size());
  }
  const double n = static_cast<double>(state.iterations());
  state.counters["tets_in"] = static_cast<double>(w.mesh.tets.size());
  state.counters["tets_out"] = static_cast<double>(out);
  state.counters["core_s"] = core_s / n;
  state.counters["service_s"] = service_s / n;
  state.counters["server_call_s"] = server_s / n;    // the call as the server timed it
  state.counters["server_input_s"] = input_s / n;    // receiving the request stream
  state.counters["server_refine_s"] = refine_s / n;  // core Refine inside the server
  state.counters["service_over_core"] = service_s / core_s;
}
BENCHMARK(BM_ServiceVsCore)
    ->Arg(58)
    ->ArgName("cells")
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->MinTime(2.0);

}  // namespace
}  // namespace tetrefine::bench

BENCHMARK_MAIN();
