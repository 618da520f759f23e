#pragma once

// Conversions between core types and tetrefine.v1 messages that are one message (or enum) each.
// The streamed parts (volume and mesh chunks) are in request_* and response_*.

#include <cstddef>
#include <cstdint>
#include <optional>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "core/refine.h"
#include "core/voxel_type.h"
#include "grpcpp/support/status.h"
#include "tetrefine/v1/tetrefine.pb.h"
#include "wire/service_limits.h"

namespace tetrefine::wire {

// What a Refine call asks for besides the volume and mesh: the core options the protocol
// carries (no callbacks, no thread count: those are the server's) plus the response shape.
struct RequestOptions {
  double epsilon = 0.1;
  int max_iterations = 16;
  std::optional<int64_t> max_tets;  // unset: the server's max_output_tets
  std::optional<double> norm_coeff;
  OutsidePolicy outside = OutsidePolicy::kReject;
  OrientationPolicy orientation = OrientationPolicy::kReject;
  int lattice_n = 8;
  int64_t lattice_max_tets = 200'000;
  uint64_t lattice_seed = 1;
  std::optional<double> min_edge_length;  // unset: the core's default
  double min_quality = RefineOptions{}.min_quality;
  bool stream_every_iteration = false;  // also send each iteration's mesh
  bool skip_final_mesh = false;         // only statistics and the summary
  uint32_t response_chunk_bytes = 0;    // 0: the server's default
};

// The request options of core `options` (callbacks and threads dropped, max_tets kept).
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
// Checks every field: INVALID_ARGUMENT naming it for a bad value or unknown enum,
// RESOURCE_EXHAUSTED for a max_tets above the server's limit.
absl::StatusOr<RequestOptions> RequestOptionsFromWire(const v1::RefineOptions& options,
                                                      const ServiceLimits& limits);
// The core options for `options`, with max_tets defaulted to the server's limit.
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

// gRPC and Abseil share canonical status codes.
grpc::Status ToGrpcStatus(const absl::Status& status);
absl::Status FromGrpcStatus(const grpc::Status& status);

}  // namespace tetrefine::wire
