#pragma once

// Conversions between core types and tetrefine.v1 messages that are one message (or enum) each.
// The streamed parts (volume and mesh chunks) are in request_* and response_*.

#include <cstddef>
#include <cstdint>
#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "core/refine.h"
#include "core/refine_options.h"
#include "core/voxel_type.h"
#include "grpcpp/support/status.h"
#include "tetrefine/v1/tetrefine.pb.h"
#include "wire/service_limits.h"

namespace tetrefine::wire {

// What a Refine call asks for besides the volume and mesh: the core options (all of them but
// `threads`, the server's business, and the callbacks, which are not sent) plus the tet budget's
// origin and the response shape. Defaults are the core's.
struct RequestOptions {
  RefineOptions refine;
  // Whether refine.max_tets is sent. When it is not, the server applies its own limit (its
  // max_output_tets, see ToCoreOptions): a caller that does not choose a budget gets the largest
  // the server allows.
  bool send_max_tets = false;
  bool stream_every_iteration = false;  // also send each iteration's mesh
  bool skip_final_mesh = false;         // only statistics and the summary
  uint32_t response_chunk_bytes = 0;    // 0: the server's default

  // Sets the tet budget and sends it.
  void SetMaxTets(int64_t max_tets) {
    refine.max_tets = max_tets;
    send_max_tets = true;
  }
};

// The request options of core `options`: its max_tets is sent; callbacks and threads are not.
RequestOptions RequestOptionsFromCore(const RefineOptions& options);

// What only the service knows about a call, besides the core result.
struct ServiceSummary {
  int64_t max_tets = 0;        // the tet budget applied
  double input_seconds = 0.0;  // receiving the input
  double total_seconds = 0.0;  // the whole call on the server
};

// Response chunk payload bounds, bytes.
inline constexpr size_t kDefaultChunkBytes = size_t{1} << 20;
inline constexpr size_t kMinResponseChunkBytes = 256;
inline constexpr size_t kMaxChunkBytes = size_t{3} << 20;

v1::VoxelType VoxelTypeToWire(VoxelType type);
absl::StatusOr<VoxelType> VoxelTypeFromWire(int type, absl::string_view field);

void RequestOptionsToWire(const RequestOptions& options, v1::RefineOptions* out);
// RESOURCE_EXHAUSTED for a max_tets above the server's limit; INVALID_ARGUMENT naming the field
// for an unknown enum value or for whatever ValidateRefineOptions (core/refine_options.h, the
// one set of limits) refuses. Unset fields keep the core's defaults.
absl::StatusOr<RequestOptions> RequestOptionsFromWire(const v1::RefineOptions& options,
                                                      const ServiceLimits& limits);
// The core options for `options`: options.refine, with max_tets the server's limit unless it was
// sent.
RefineOptions ToCoreOptions(const RequestOptions& options, const ServiceLimits& limits);

void IterationStatsToWire(const IterationStats& stats, v1::IterationStats* out);
absl::StatusOr<IterationStats> IterationStatsFromWire(const v1::IterationStats& stats);

void SummaryToWire(const RefineResult& result, const ServiceSummary& service, int64_t input_tets,
                   v1::Summary* out);
// Fills the summary fields of `result` (not the mesh, per-tet arrays or iterations).
absl::Status SummaryFromWire(const v1::Summary& summary, RefineResult* result,
                             ServiceSummary* service);

void LimitsToWire(const ServiceLimits& limits, v1::ServerLimits* out);
ServiceLimits LimitsFromWire(const v1::ServerLimits& limits);

// The bytes one label of `labels` can take in a TetLabelChunk (a varint int32): the most any of
// them takes, 1 to 5, or 10 when one is negative (sign-extended to 64 bits). Chunks sized at 4
// bytes a label ran past a server's --max_message_bytes for negative labels (found 2026-11-28:
// 20,000 labels of -1 in an 82 KB message against a 64 KB limit).
size_t LabelWireBytes(const std::vector<int32_t>& labels);

// gRPC and Abseil share canonical status codes.
grpc::Status ToGrpcStatus(const absl::Status& status);
absl::Status FromGrpcStatus(const grpc::Status& status);

}  // namespace tetrefine::wire
