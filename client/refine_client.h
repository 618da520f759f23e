#pragma once

// Client of the tetrefine.v1 Refiner service: the same inputs and result as core Refine, over a
// gRPC channel (remote, or in process via server::EmbeddedServer).

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <string_view>

#include "absl/status/statusor.h"
#include "core/mesh.h"
#include "core/refine.h"
#include "core/volume.h"
#include "grpcpp/channel.h"
#include "wire/conversion.h"
#include "wire/response_reader.h"
#include "wire/service_limits.h"

namespace tetrefine::client {

// Tuning sent to the server: core RefineOptions minus callbacks and threads, with an optional
// max_tets (unset: the server's limit) and the response shape. Build from core options with
// wire::RequestOptionsFromCore.
using RefineRequestOptions = wire::RequestOptions;

// The core result (mesh, tet_iteration, tet_quality, iterations, stop reason, qualities,
// lattice, norm_coeff, ...) exactly as core Refine returns it, plus `service`: the tet budget
// applied and the server's timings.
using ClientResult = wire::RefineReply;

struct RefineCallbacks {
  // Each iteration's statistics, as soon as the server has finished the iteration.
  std::function<void(const IterationStats&)> on_iteration;
  // Set: the server also streams each iteration's mesh (points, tets, values), passed here.
  std::function<void(int iteration, const Mesh& mesh)> on_mesh;
  // Polled about every 10 ms from a helper thread while the call runs; true cancels it.
  std::function<bool()> should_cancel;
  // Progress of the call's phases, for reporting; each is called at most once, in this order,
  // on the calling thread, between the on_iteration calls where they fall.
  // The whole request has been written (`bytes`: its messages' serialized size). The server
  // validates it and refines next.
  std::function<void(int64_t bytes)> on_input_sent;
  // The final mesh's header has arrived: refinement and the server's final checks (the stop
  // test, the lattice check) are done; `vertices` and `tets` of the mesh whose chunks follow.
  std::function<void(int64_t vertices, int64_t tets)> on_result_started;
  // The summary has arrived: the response is complete (`bytes`: the serialized size of the
  // messages from the final mesh's header to the summary).
  std::function<void(int64_t bytes)> on_result_received;
  // Something the caller should be told that did not stop the call: a sharded run's part that
  // failed on one server and was retried on another (client/sharding). One line, no prefix.
  std::function<void(const std::string& message)> on_warning;
};

struct CallOptions {
  size_t chunk_bytes = size_t{1} << 20;  // request chunk payload, bytes (>= 1 element a chunk)
  std::optional<std::chrono::system_clock::time_point> deadline;
  // Wait for the server to become reachable (up to the deadline) instead of failing with
  // UNAVAILABLE at once.
  bool wait_for_ready = false;
  // Non-empty: sent as call metadata "authorization: Bearer <token>", for a server started with
  // --token_file.
  std::string bearer_token;
};

// Refines `mesh` in `volume` (a whole volume or a slab of one) on the server behind `channel`.
// Errors are the server's status (INVALID_ARGUMENT, RESOURCE_EXHAUSTED, DEADLINE_EXCEEDED,
// UNAVAILABLE, ...); a call cancelled through should_cancel is CANCELLED (unlike core Refine,
// no partial result comes back).
absl::StatusOr<ClientResult> RefineViaService(std::shared_ptr<grpc::Channel> channel,
                                              const Volume& volume, const Mesh& mesh,
                                              const RefineRequestOptions& options,
                                              const RefineCallbacks& callbacks = {},
                                              const CallOptions& call = {});

struct ServerInfo {
  std::string version;
  wire::ServiceLimits limits;
};

// `bearer_token` as in CallOptions.
absl::StatusOr<ServerInfo> GetServerInfo(
    std::shared_ptr<grpc::Channel> channel,
    std::optional<std::chrono::system_clock::time_point> deadline = std::nullopt,
    const std::string& bearer_token = "");

// The request chunk size to use with a server whose largest accepted message is
// `max_message_bytes`: `preferred`, lowered so that a chunk and its message framing fit.
size_t ChunkBytesFor(int64_t max_message_bytes, size_t preferred = size_t{1} << 20);

// grpc.health.v1 serving status.
enum class ServingStatus { kUnknown, kServing, kNotServing, kServiceUnknown };

// Asks the grpc.health.v1 service about `service` ("": the server as a whole;
// "tetrefine.v1.Refiner": the refiner). An RPC failure is its status (e.g. NOT_FOUND for an
// unknown service, UNAVAILABLE for no server).
absl::StatusOr<ServingStatus> CheckHealth(
    std::shared_ptr<grpc::Channel> channel, std::string_view service = "",
    std::optional<std::chrono::system_clock::time_point> deadline = std::nullopt);

}  // namespace tetrefine::client
