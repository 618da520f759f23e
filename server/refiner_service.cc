#include "server/refiner_service.h"

#include <chrono>
#include <string>

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

RefinerService::RefinerService(const ServiceConfig& config)
    : config_(config),
      gate_(CallGate::Config{.slots = config.limits.max_concurrent_refinements,
                             .max_calls_per_identity = config.limits.max_calls_per_identity,
                             .max_slots_per_identity = config.max_slots_per_identity,
                             .max_input_bytes_per_identity = config.max_input_bytes_per_identity,
                             .max_bytes_per_identity = config.max_bytes_per_identity,
                             .memory_budget_bytes = config.limits.memory_budget_bytes}) {}

RefinerService::~RefinerService() {
  // Calls end promptly once gRPC has cancelled them (server Shutdown); their refinement threads
  // hold what the calls use until then.
  gate_.WaitUntilIdle(std::chrono::steady_clock::time_point::max());
}

grpc::ServerBidiReactor<v1::RefineRequest, v1::RefineResponse>* RefinerService::Refine(
    grpc::CallbackServerContext* context) {
  return RefineCall::Start(context, RefineCall::Environment{.config = &config_,
                                                            .gate = &gate_,
                                                            .watchdog = &watchdog_,
                                                            .refusal_log = &refusal_log_});
}

namespace {

// Whether `request` parses as a GetServerInfoRequest, by gRPC's own deserialiser. It consumes the
// buffer it reads: it reads a copy, which shares the slices.
bool IsServerInfoRequest(const grpc::ByteBuffer& request) {
  grpc::ByteBuffer body(request);
  v1::GetServerInfoRequest parsed;
  return grpc::SerializationTraits<v1::GetServerInfoRequest>::Deserialize(&body, &parsed).ok();
}

}  // namespace

grpc::ServerUnaryReactor* RefinerService::GetServerInfo(grpc::CallbackServerContext* context,
                                                        const grpc::ByteBuffer* request,
                                                        grpc::ByteBuffer* response) {
  grpc::ServerUnaryReactor* reactor = context->DefaultReactor();
  absl::StatusOr<std::string> identity = IdentifyCall(config_.access, *context);
  grpc::Status status = identity.ok() ? grpc::Status::OK : wire::ToGrpcStatus(identity.status());
  if (!status.ok()) {
    // Clients ask this before they refine, so a wrong token or certificate ends here: the
    // operator must see it (an operator sweep found three refused CLI runs left no trace).
    // At most 20 refusals a second, with Refine's (a flood wrote 47 MB of log in 15 s).
    if (int64_t unlogged = 0; refusal_log_.Allow(&unlogged)) {
      spdlog::warn("GetServerInfo peer={} refused: {} {}{}", context->peer(),
                   absl::StatusCodeToString(identity.status().code()),
                   std::string(identity.status().message()),
                   LogRateLimit::SuppressedNote(unlogged));
    }
  } else if (!IsServerInfoRequest(*request)) {
    status = grpc::Status(grpc::StatusCode::INVALID_ARGUMENT,
                          absl::StrCat("GetServerInfo: the request (", request->Length(),
                                       " bytes) did not parse as a GetServerInfoRequest"));
  } else {
    v1::ServerInfo info;
    info.set_version(TETREFINE_VERSION);
    wire::LimitsToWire(config_.limits, info.mutable_limits());
    bool own_buffer = false;
    status = grpc::SerializationTraits<v1::ServerInfo>::Serialize(info, response, &own_buffer);
  }
  if (config_.metrics != nullptr) config_.metrics->RecordServerInfo(status.error_code());
  reactor->Finish(status);
  return reactor;
}

}  // namespace tetrefine::server
