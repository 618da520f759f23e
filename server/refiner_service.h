#pragma once

#include <atomic>
#include <memory>

#include "grpcpp/grpcpp.h"
#include "tetrefine/v1/tetrefine.grpc.pb.h"
#include "wire/service_limits.h"

namespace tetrefine::server {

class ServiceMetrics;  // server/metrics.h

struct ServiceConfig {
  wire::ServiceLimits limits;
  int refine_threads = 0;                   // core worker threads per refinement; 0: all cores
  std::shared_ptr<ServiceMetrics> metrics;  // null: no metrics recorded
};

// The tetrefine.v1.Refiner service. Stateless: a call keeps nothing once it returns; the only
// shared state is the count of refinements in flight, which enforces the concurrency limit.
class RefinerService final : public v1::Refiner::Service {
 public:
  explicit RefinerService(const ServiceConfig& config) : config_(config) {}

  grpc::Status Refine(
      grpc::ServerContext* context,
      grpc::ServerReaderWriter<v1::RefineResponse, v1::RefineRequest>* stream) override;

  grpc::Status GetServerInfo(grpc::ServerContext* context, const v1::GetServerInfoRequest* request,
                             v1::ServerInfo* response) override;

  // Refine calls admitted and not yet returned.
  int active_refinements() const { return active_.load(); }

  // From now on every new Refine call is refused with UNAVAILABLE; calls already admitted run on.
  // The first step of a graceful shutdown, taken while the listener still accepts connections.
  void StopAdmitting() { admitting_.store(false); }

  const ServiceConfig& config() const { return config_; }

 private:
  ServiceConfig config_;
  std::atomic<int> active_{0};
  std::atomic<bool> admitting_{true};
};

}  // namespace tetrefine::server
