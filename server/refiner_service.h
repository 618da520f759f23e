#pragma once

#include <memory>

#include "grpcpp/grpcpp.h"
#include "server/call_gate.h"
#include "server/identity.h"
#include "server/log_rate_limit.h"
#include "server/watchdog.h"
#include "tetrefine/v1/tetrefine.grpc.pb.h"
#include "wire/service_limits.h"

namespace tetrefine::server {

class ServiceMetrics;  // server/metrics.h

struct ServiceConfig {
  // Sizes, caps, time limits, per-identity quota and memory budget (all advertised by
  // GetServerInfo). The defaults suit an embedded service: no time limits, no quota, no budget.
  wire::ServiceLimits limits;
  int refine_threads = 0;  // core worker threads per refinement; 0: all cores
  // Refinement slots one identity holds at once (server/call_gate.h); 0: no cap.
  int max_slots_per_identity = 0;
  // Memory one identity's uploading calls may hold (server/call_gate.h); 0: no cap.
  int64_t max_input_bytes_per_identity = 0;
  // Memory all of one identity's calls may hold together (server/call_gate.h); 0: no cap.
  int64_t max_bytes_per_identity = 0;
  std::shared_ptr<ServiceMetrics> metrics;  // null: no metrics recorded
  AccessPolicy access;                      // tokens and certificate allow-list; none by default
};

// The tetrefine.v1.Refiner service. Refine is a callback (reactor) method, so a call that sends
// nothing costs no thread; GetServerInfo is synchronous. Stateless between calls: what a call
// holds (server/call_gate.h) is released when it ends.
// GetServerInfo is a raw method (bytes in, bytes out), parsed here: a request that does not
// parse is answered INVALID_ARGUMENT naming the method and the size, where gRPC's own parse
// answered INTERNAL with an empty message (an outside review, 2026-11-29).
class RefinerService final : public v1::Refiner::WithRawCallbackMethod_GetServerInfo<
                                 v1::Refiner::WithCallbackMethod_Refine<v1::Refiner::Service>> {
 public:
  explicit RefinerService(const ServiceConfig& config);
  // Waits until every call has ended and released what it held (the server must have been shut
  // down, which cancels what still runs).
  ~RefinerService() override;

  grpc::ServerBidiReactor<v1::RefineRequest, v1::RefineResponse>* Refine(
      grpc::CallbackServerContext* context) override;

  grpc::ServerUnaryReactor* GetServerInfo(grpc::CallbackServerContext* context,
                                          const grpc::ByteBuffer* request,
                                          grpc::ByteBuffer* response) override;

  // Refine calls open (reading input, queued, refining or writing results).
  int open_calls() const { return gate_.open_calls(); }
  // Refinements running: slots taken.
  int running_refinements() const { return gate_.running(); }

  // From now on every new Refine call is refused with UNAVAILABLE; open calls carry on. The
  // first step of a graceful shutdown, taken while the listener still accepts connections.
  void StopAdmitting() { gate_.StopAdmitting(); }
  // Waits until no call is open or `deadline` passes; true if none is.
  bool WaitUntilIdle(std::chrono::steady_clock::time_point deadline) {
    return gate_.WaitUntilIdle(deadline);
  }

  const ServiceConfig& config() const { return config_; }
  CallGate& gate() { return gate_; }

 private:
  ServiceConfig config_;
  Watchdog watchdog_;
  CallGate gate_;
  LogRateLimit refusal_log_{20};  // access lines of refused calls, Refine's and GetServerInfo's
};

}  // namespace tetrefine::server
