#include "server/refine_call.h"

#include <atomic>
#include <chrono>
#include <mutex>
#include <span>
#include <string>
#include <utility>

#include "absl/strings/str_cat.h"
#include "core/refine.h"
#include "wire/conversion.h"
#include "wire/request_reader.h"
#include "wire/response_writer.h"

namespace tetrefine::server {
namespace {

using Clock = std::chrono::steady_clock;

double SecondsSince(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

bool DeadlinePassed(const grpc::ServerContext* context) {
  return std::chrono::system_clock::now() >= context->deadline();
}

// The status for a call that stopped because the client went away or time ran out.
grpc::Status Interrupted(const grpc::ServerContext* context, absl::string_view during) {
  if (DeadlinePassed(context)) {
    return grpc::Status(grpc::StatusCode::DEADLINE_EXCEEDED,
                        absl::StrCat("deadline exceeded during ", during));
  }
  return grpc::Status(grpc::StatusCode::CANCELLED, absl::StrCat("cancelled during ", during));
}

// The core's should_cancel. The core polls it from every worker thread; ServerContext::
// IsCancelled plucks the call's completion queue, which allows only a few concurrent pluckers, so
// one thread at a time asks it and the others reuse the last answer.
class CancellationProbe {
 public:
  CancellationProbe(grpc::ServerContext* context, const std::atomic<bool>* broken)
      : context_(context), broken_(broken) {}

  bool operator()() {
    if (cancelled_.load(std::memory_order_relaxed)) return true;
    std::unique_lock<std::mutex> lock(mu_, std::try_to_lock);
    if (!lock.owns_lock()) return false;
    if (broken_->load() || context_->IsCancelled() || DeadlinePassed(context_)) {
      cancelled_.store(true);
    }
    return cancelled_.load();
  }

 private:
  grpc::ServerContext* context_;
  const std::atomic<bool>* broken_;
  std::mutex mu_;
  std::atomic<bool> cancelled_{false};
};

absl::StatusOr<wire::RefineInput> ReadInput(const ServiceConfig& config,
                                            grpc::ServerContext* context, RefineStream* stream,
                                            CallRecord* record) {
  wire::RequestReader reader(config.limits);
  v1::RefineRequest request;
  while (!reader.complete()) {
    if (!stream->Read(&request)) {
      record->bytes_in = reader.bytes_received();
      if (context->IsCancelled()) return absl::CancelledError("input");
      return reader.IncompleteError();
    }
    absl::Status status = reader.Add(request);
    record->bytes_in = reader.bytes_received();
    if (!status.ok()) return status;
  }
  record->tets_in = reader.tets_declared();
  return reader.Take();
}

}  // namespace

grpc::Status RunRefineCall(const ServiceConfig& config, grpc::ServerContext* context,
                           RefineStream* stream, CallRecord* record) {
  const Clock::time_point start = Clock::now();
  absl::StatusOr<wire::RefineInput> input = ReadInput(config, context, stream, record);
  if (!input.ok()) {
    if (absl::IsCancelled(input.status())) return Interrupted(context, "input");
    return wire::ToGrpcStatus(input.status());
  }
  const double input_seconds = SecondsSince(start);

  const wire::RequestOptions& request_options = input->options;
  RefineOptions options = wire::ToCoreOptions(request_options, config.limits);
  options.threads = config.refine_threads;

  wire::ResponseWriter writer(request_options.response_chunk_bytes,
                              [stream](const v1::RefineResponse& r) { return stream->Write(r); });
  // Set when a write fails: the client is gone, so the work is pointless.
  std::atomic<bool> broken{false};
  options.on_iteration = [&](const IterationStats& stats, const Mesh& mesh) {
    if (broken.load()) return;
    bool ok = writer.WriteIterationStats(stats);
    if (ok && request_options.stream_every_iteration) {
      ok = writer.WriteMesh(stats.iteration, /*final=*/false, mesh, {}, {});
    }
    if (!ok) broken.store(true);
  };
  CancellationProbe probe(context, &broken);
  options.should_cancel = [&probe] { return probe(); };

  absl::StatusOr<RefineResult> result = Refine(input->volume, input->mesh, options);
  if (!result.ok()) return wire::ToGrpcStatus(result.status());
  record->iterations = static_cast<int>(result->iterations.size());
  record->tets_out = static_cast<int64_t>(result->mesh.tets.size());
  if (result->stop_reason == StopReason::kCancelled || broken.load() || context->IsCancelled()) {
    return Interrupted(context,
                       absl::StrCat("refinement, after ", record->iterations, " iterations"));
  }

  if (!request_options.skip_final_mesh &&
      !writer.WriteMesh(record->iterations, /*final=*/true, result->mesh,
                        std::span<const int32_t>(result->tet_iteration),
                        std::span<const float>(result->tet_quality))) {
    return Interrupted(context, "output");
  }
  const wire::ServiceSummary service{.max_tets = options.max_tets,
                                     .input_seconds = input_seconds,
                                     .total_seconds = SecondsSince(start)};
  if (!writer.WriteSummary(*result, service, record->tets_in)) {
    return Interrupted(context, "output");
  }
  return grpc::Status::OK;
}

}  // namespace tetrefine::server
