#include "server/refiner_service.h"

#include <chrono>

#include "absl/status/status.h"
#include "absl/strings/str_cat.h"
#include "server/metrics.h"
#include "server/refine_call.h"
#include "spdlog/spdlog.h"
#include "wire/conversion.h"

#ifndef TETREFINE_VERSION
#define TETREFINE_VERSION "unknown"
#endif

namespace tetrefine::server {
namespace {

// Holds one of `limit` slots of `active` for its lifetime, if one was free.
class Slot {
 public:
  Slot(std::atomic<int>& active, int limit) : active_(active) {
    acquired_ = active_.fetch_add(1) < limit;
    if (!acquired_) active_.fetch_sub(1);
  }
  ~Slot() {
    if (acquired_) active_.fetch_sub(1);
  }
  Slot(const Slot&) = delete;
  Slot& operator=(const Slot&) = delete;
  bool acquired() const { return acquired_; }

 private:
  std::atomic<int>& active_;
  bool acquired_;
};

}  // namespace

grpc::Status RefinerService::Refine(grpc::ServerContext* context, RefineStream* stream) {
  const auto start = std::chrono::steady_clock::now();
  CallRecord record;
  grpc::Status status;
  bool admitted = false;
  {
    Slot slot(active_, config_.limits.max_concurrent_refinements);
    // Checked after taking the slot: a shutdown that sees no active call after StopAdmitting
    // knows that no call will start.
    admitted = slot.acquired() && admitting_.load();
    if (admitted) {
      ServiceMetrics::InFlight in_flight(config_.metrics.get());
      status = RunRefineCall(config_, context, stream, &record);
    } else if (!admitting_.load()) {
      status = grpc::Status(grpc::StatusCode::UNAVAILABLE,
                            "this server is shutting down; retry on another");
    } else {
      status = grpc::Status(grpc::StatusCode::RESOURCE_EXHAUSTED,
                            absl::StrCat("this server already runs its limit of ",
                                         config_.limits.max_concurrent_refinements,
                                         " concurrent refinements; retry later"));
    }
  }
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (config_.metrics != nullptr) {
    config_.metrics->RecordCall({.code = status.error_code(),
                                 .admitted = admitted,
                                 .seconds = seconds,
                                 .bytes_in = record.bytes_in,
                                 .tets_in = record.tets_in,
                                 .tets_out = record.tets_out});
  }
  spdlog::info(
      "Refine peer={} bytes_in={} tets_in={} tets_out={} iterations={} duration={:.3f}s "
      "status={} {}",
      context->peer(), record.bytes_in, record.tets_in, record.tets_out, record.iterations, seconds,
      absl::StatusCodeToString(static_cast<absl::StatusCode>(status.error_code())),
      status.error_message());
  return status;
}

grpc::Status RefinerService::GetServerInfo(grpc::ServerContext* /*context*/,
                                           const v1::GetServerInfoRequest* /*request*/,
                                           v1::ServerInfo* response) {
  response->set_version(TETREFINE_VERSION);
  wire::LimitsToWire(config_.limits, response->mutable_limits());
  return grpc::Status::OK;
}

}  // namespace tetrefine::server
