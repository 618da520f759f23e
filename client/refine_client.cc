#include "client/refine_client.h"

#include <algorithm>
#include <atomic>
#include <thread>
#include <utility>

#include "grpc/health/v1/health.grpc.pb.h"
#include "grpcpp/grpcpp.h"
#include "tetrefine/v1/tetrefine.grpc.pb.h"
#include "wire/request_writer.h"

namespace tetrefine::client {
namespace {

void ApplyDeadline(const std::optional<std::chrono::system_clock::time_point>& deadline,
                   grpc::ClientContext* context) {
  if (deadline.has_value()) context->set_deadline(*deadline);
}

void ApplyToken(const std::string& token, grpc::ClientContext* context) {
  if (!token.empty()) context->AddMetadata("authorization", "Bearer " + token);
}

// Room for a request message's framing around a chunk's payload: the oneof tag, the chunk's
// start index or offset and the payload's length prefix, each a few bytes.
constexpr int64_t kMessageOverheadBytes = 64;

// Cancels `context` once should_cancel() says so, polling until destroyed. Blocking reads give
// the caller no other chance to stop a long iteration.
class CancelWatcher {
 public:
  CancelWatcher(std::function<bool()> should_cancel, grpc::ClientContext* context) {
    if (!should_cancel) return;
    thread_ = std::jthread(
        [should_cancel = std::move(should_cancel), context, this](std::stop_token stop) {
          while (!stop.stop_requested()) {
            if (should_cancel()) {
              cancelled_.store(true);
              context->TryCancel();
              return;
            }
            std::this_thread::sleep_for(std::chrono::milliseconds(10));
          }
        });
  }
  bool cancelled() const { return cancelled_.load(); }

 private:
  std::atomic<bool> cancelled_{false};
  std::jthread thread_;  // last: joined before the flag goes away
};

}  // namespace

absl::StatusOr<ClientResult> RefineViaService(std::shared_ptr<grpc::Channel> channel,
                                              const Volume& volume, const Mesh& mesh,
                                              const RefineRequestOptions& options,
                                              const RefineCallbacks& callbacks,
                                              const CallOptions& call) {
  RefineRequestOptions sent = options;
  if (callbacks.on_mesh) sent.stream_every_iteration = true;

  v1::Refiner::Stub stub(channel);
  grpc::ClientContext context;
  ApplyDeadline(call.deadline, &context);
  ApplyToken(call.bearer_token, &context);
  context.set_wait_for_ready(call.wait_for_ready);
  auto stream = stub.Refine(&context);
  absl::Status reader_status;
  {
    CancelWatcher watcher(callbacks.should_cancel, &context);
    // The server reads the whole input before it answers, so writing everything first cannot
    // deadlock. A failed write means the server has already ended the call: its status tells.
    int64_t bytes_sent = 0;
    if (wire::WriteRequest(sent, volume, mesh, call.chunk_bytes, [&](const v1::RefineRequest& r) {
          bytes_sent += static_cast<int64_t>(r.ByteSizeLong());
          return stream->Write(r);
        })) {
      stream->WritesDone();
      if (callbacks.on_input_sent) callbacks.on_input_sent(bytes_sent);
    }
    wire::ResponseReader reader(callbacks.on_iteration, callbacks.on_mesh, !sent.skip_final_mesh);
    v1::RefineResponse response;
    // Bytes of the result (final mesh and summary) received so far; -1 before its start.
    int64_t result_bytes = -1;
    while (reader_status.ok() && stream->Read(&response)) {
      const bool result_start =
          response.kind_case() == v1::RefineResponse::kMeshHeader && response.mesh_header().final();
      // A skipped final mesh: the summary is the whole result.
      if (result_start || (result_bytes < 0 && response.has_summary())) result_bytes = 0;
      if (result_bytes >= 0) result_bytes += static_cast<int64_t>(response.ByteSizeLong());
      reader_status = reader.Add(response);
      if (!reader_status.ok()) break;
      if (result_start && callbacks.on_result_started) {
        callbacks.on_result_started(response.mesh_header().vertex_count(),
                                    response.mesh_header().tet_count());
      }
      if (response.has_summary() && callbacks.on_result_received) {
        callbacks.on_result_received(result_bytes);
      }
    }
    if (!reader_status.ok()) context.TryCancel();
    grpc::Status status = stream->Finish();
    if (!reader_status.ok()) return reader_status;
    if (!status.ok()) {
      if (watcher.cancelled()) return absl::CancelledError("cancelled by should_cancel");
      return wire::FromGrpcStatus(status);
    }
    if (!reader.complete()) {
      return absl::InternalError("the Refine response stream ended before its summary");
    }
    return reader.Take();
  }
}

size_t ChunkBytesFor(int64_t max_message_bytes, size_t preferred) {
  const int64_t room = max_message_bytes - kMessageOverheadBytes;
  // At least one element (a vertex, 24 bytes) must fit; a server advertising less cannot be
  // sent a mesh at all, and its refusal will say so.
  return static_cast<size_t>(std::clamp<int64_t>(room, 24, static_cast<int64_t>(preferred)));
}

absl::StatusOr<ServerInfo> GetServerInfo(
    std::shared_ptr<grpc::Channel> channel,
    std::optional<std::chrono::system_clock::time_point> deadline,
    const std::string& bearer_token) {
  v1::Refiner::Stub stub(channel);
  grpc::ClientContext context;
  ApplyDeadline(deadline, &context);
  ApplyToken(bearer_token, &context);
  v1::ServerInfo info;
  grpc::Status status = stub.GetServerInfo(&context, v1::GetServerInfoRequest(), &info);
  if (!status.ok()) return wire::FromGrpcStatus(status);
  return ServerInfo{.version = info.version(), .limits = wire::LimitsFromWire(info.limits())};
}

absl::StatusOr<ServingStatus> CheckHealth(
    std::shared_ptr<grpc::Channel> channel, std::string_view service,
    std::optional<std::chrono::system_clock::time_point> deadline) {
  grpc::health::v1::Health::Stub stub(channel);
  grpc::ClientContext context;
  ApplyDeadline(deadline, &context);
  grpc::health::v1::HealthCheckRequest request;
  request.set_service(std::string(service));
  grpc::health::v1::HealthCheckResponse response;
  grpc::Status status = stub.Check(&context, request, &response);
  if (!status.ok()) return wire::FromGrpcStatus(status);
  switch (response.status()) {
    case grpc::health::v1::HealthCheckResponse::SERVING:
      return ServingStatus::kServing;
    case grpc::health::v1::HealthCheckResponse::NOT_SERVING:
      return ServingStatus::kNotServing;
    case grpc::health::v1::HealthCheckResponse::SERVICE_UNKNOWN:
      return ServingStatus::kServiceUnknown;
    default:
      return ServingStatus::kUnknown;
  }
}

}  // namespace tetrefine::client
