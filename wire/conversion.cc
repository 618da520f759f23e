#include "wire/conversion.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "absl/strings/str_cat.h"
#include "google/protobuf/io/coded_stream.h"

namespace tetrefine::wire {
namespace {

absl::Status Invalid(absl::string_view field, absl::string_view what) {
  return absl::InvalidArgumentError(absl::StrCat("options.", field, ": ", what));
}

void QualityToWire(const QualityStats& q, v1::QualityStats* out) {
  out->set_min(q.min);
  out->set_mean(q.mean);
  out->set_count(q.count);
}

QualityStats QualityFromWire(const v1::QualityStats& q) {
  return QualityStats{.min = q.min(), .mean = q.mean(), .count = q.count()};
}

v1::StopReason StopReasonToWire(StopReason r) {
  switch (r) {
    case StopReason::kConverged:
      return v1::STOP_REASON_CONVERGED;
    case StopReason::kMaxIterations:
      return v1::STOP_REASON_MAX_ITERATIONS;
    case StopReason::kTetBudget:
      return v1::STOP_REASON_TET_BUDGET;
    case StopReason::kCancelled:
      return v1::STOP_REASON_CANCELLED;
    case StopReason::kQualityFloor:
      return v1::STOP_REASON_QUALITY_FLOOR;
    case StopReason::kMinEdgeLength:
      return v1::STOP_REASON_MIN_EDGE_LENGTH;
  }
  return v1::STOP_REASON_UNSPECIFIED;
}

absl::StatusOr<StopReason> StopReasonFromWire(int r) {
  switch (r) {
    case v1::STOP_REASON_CONVERGED:
      return StopReason::kConverged;
    case v1::STOP_REASON_MAX_ITERATIONS:
      return StopReason::kMaxIterations;
    case v1::STOP_REASON_TET_BUDGET:
      return StopReason::kTetBudget;
    case v1::STOP_REASON_CANCELLED:
      return StopReason::kCancelled;
    case v1::STOP_REASON_QUALITY_FLOOR:
      return StopReason::kQualityFloor;
    case v1::STOP_REASON_MIN_EDGE_LENGTH:
      return StopReason::kMinEdgeLength;
    default:
      return absl::DataLossError(absl::StrCat("summary.stop_reason: unknown value ", r));
  }
}

v1::RefineScheme RefineSchemeToWire(RefineScheme s) {
  switch (s) {
    case RefineScheme::kPaper:
      return v1::REFINE_SCHEME_PAPER;
    case RefineScheme::kLongestEdge:
      return v1::REFINE_SCHEME_LONGEST_EDGE;
  }
  return v1::REFINE_SCHEME_UNSPECIFIED;
}

}  // namespace

RequestOptions RequestOptionsFromCore(const RefineOptions& options) {
  RequestOptions out;
  out.refine = options;
  out.refine.threads = 0;
  out.refine.on_iteration = nullptr;
  out.refine.should_cancel = nullptr;
  out.send_max_tets = true;
  return out;
}

v1::VoxelType VoxelTypeToWire(VoxelType type) {
  switch (type) {
    case VoxelType::kUint8:
      return v1::VOXEL_TYPE_UINT8;
    case VoxelType::kInt16:
      return v1::VOXEL_TYPE_INT16;
    case VoxelType::kUint16:
      return v1::VOXEL_TYPE_UINT16;
    case VoxelType::kInt32:
      return v1::VOXEL_TYPE_INT32;
    case VoxelType::kFloat32:
      return v1::VOXEL_TYPE_FLOAT32;
    case VoxelType::kFloat64:
      return v1::VOXEL_TYPE_FLOAT64;
  }
  return v1::VOXEL_TYPE_UNSPECIFIED;
}

absl::StatusOr<VoxelType> VoxelTypeFromWire(int type, absl::string_view field) {
  switch (type) {
    case v1::VOXEL_TYPE_UINT8:
      return VoxelType::kUint8;
    case v1::VOXEL_TYPE_INT16:
      return VoxelType::kInt16;
    case v1::VOXEL_TYPE_UINT16:
      return VoxelType::kUint16;
    case v1::VOXEL_TYPE_INT32:
      return VoxelType::kInt32;
    case v1::VOXEL_TYPE_FLOAT32:
      return VoxelType::kFloat32;
    case v1::VOXEL_TYPE_FLOAT64:
      return VoxelType::kFloat64;
    default:
      return absl::InvalidArgumentError(
          absl::StrCat(field, ": unknown or unspecified voxel type ", type));
  }
}

void RequestOptionsToWire(const RequestOptions& o, v1::RefineOptions* out) {
  const RefineOptions& r = o.refine;
  out->set_epsilon(r.epsilon);
  out->set_max_iterations(r.max_iterations);
  if (o.send_max_tets) out->set_max_tets(r.max_tets);
  if (r.norm_coeff.has_value()) out->set_norm_coeff(*r.norm_coeff);
  out->set_outside_policy(r.outside == OutsidePolicy::kClamp ? v1::OUTSIDE_POLICY_CLAMP
                                                             : v1::OUTSIDE_POLICY_REJECT);
  out->set_orientation_policy(r.orientation == OrientationPolicy::kNormalize
                                  ? v1::ORIENTATION_POLICY_NORMALIZE
                                  : v1::ORIENTATION_POLICY_REJECT);
  out->set_lattice_n(r.lattice_n);
  out->set_lattice_max_tets(r.lattice_max_tets);
  out->set_lattice_seed(r.lattice_seed);
  if (r.min_edge_length.has_value()) out->set_min_edge_length(*r.min_edge_length);
  if (r.min_quality.has_value()) out->set_min_quality(*r.min_quality);
  if (r.quality_reference.has_value()) out->set_quality_reference(*r.quality_reference);
  out->set_scheme(RefineSchemeToWire(r.scheme));
  out->set_certify(r.certify);
  out->set_track_parents(r.track_parents);
  out->set_stream_every_iteration(o.stream_every_iteration);
  out->set_skip_final_mesh(o.skip_final_mesh);
  out->set_response_chunk_bytes(o.response_chunk_bytes);
}

absl::StatusOr<RequestOptions> RequestOptionsFromWire(const v1::RefineOptions& in,
                                                      const ServiceLimits& limits) {
  RequestOptions o;
  RefineOptions& r = o.refine;
  // Values are checked once, below, by the core's own validation: one set of limits.
  if (in.has_epsilon()) r.epsilon = in.epsilon();
  if (in.has_max_iterations()) r.max_iterations = in.max_iterations();
  if (in.has_max_tets()) {
    if (in.max_tets() > limits.max_output_tets) {
      return absl::ResourceExhaustedError(
          absl::StrCat("options.max_tets: ", in.max_tets(), " exceeds this server's limit of ",
                       limits.max_output_tets, " output tets (--max_output_tets)"));
    }
    r.max_tets = in.max_tets();
    o.send_max_tets = true;
  }
  if (in.has_norm_coeff()) r.norm_coeff = in.norm_coeff();
  switch (in.outside_policy()) {
    case v1::OUTSIDE_POLICY_UNSPECIFIED:
    case v1::OUTSIDE_POLICY_REJECT:
      r.outside = OutsidePolicy::kReject;
      break;
    case v1::OUTSIDE_POLICY_CLAMP:
      r.outside = OutsidePolicy::kClamp;
      break;
    default:
      return Invalid("outside_policy", absl::StrCat("unknown value ", in.outside_policy()));
  }
  switch (in.orientation_policy()) {
    case v1::ORIENTATION_POLICY_UNSPECIFIED:
    case v1::ORIENTATION_POLICY_REJECT:
      r.orientation = OrientationPolicy::kReject;
      break;
    case v1::ORIENTATION_POLICY_NORMALIZE:
      r.orientation = OrientationPolicy::kNormalize;
      break;
    default:
      return Invalid("orientation_policy", absl::StrCat("unknown value ", in.orientation_policy()));
  }
  if (in.has_lattice_n()) r.lattice_n = in.lattice_n();
  if (in.has_lattice_max_tets()) r.lattice_max_tets = in.lattice_max_tets();
  if (in.has_lattice_seed()) r.lattice_seed = in.lattice_seed();
  if (in.has_min_edge_length()) r.min_edge_length = in.min_edge_length();
  if (in.has_min_quality()) r.min_quality = in.min_quality();
  if (in.has_quality_reference()) r.quality_reference = in.quality_reference();
  switch (in.scheme()) {
    case v1::REFINE_SCHEME_UNSPECIFIED:
      break;  // the core's default
    case v1::REFINE_SCHEME_PAPER:
      r.scheme = RefineScheme::kPaper;
      break;
    case v1::REFINE_SCHEME_LONGEST_EDGE:
      r.scheme = RefineScheme::kLongestEdge;
      break;
    default:
      return Invalid("scheme", absl::StrCat("unknown value ", in.scheme()));
  }
  r.certify = in.certify();
  r.track_parents = in.track_parents();
  if (absl::Status valid = ValidateRefineOptions(r); !valid.ok()) return valid;
  // This server's own bounds, beyond the core's: a normal norm_coeff, and the work caps.
  if (r.norm_coeff.has_value() && !std::isnormal(*r.norm_coeff)) {
    // A subnormal normalisation turns every error into inf (5e-324 did); the bound that depends
    // on the volume's range follows once the volume has arrived (wire/request_reader.cc).
    return Invalid("norm_coeff",
                   absl::StrCat("must be a normal number (>= ", std::numeric_limits<double>::min(),
                                "), got ", *r.norm_coeff));
  }
  if (r.max_iterations > limits.max_iterations) {
    return absl::ResourceExhaustedError(absl::StrCat(
        "options.max_iterations: ", r.max_iterations, " exceeds this server's limit of ",
        limits.max_iterations, " iterations (--max_iterations)"));
  }
  if (r.lattice_n > limits.max_lattice_n) {
    return absl::ResourceExhaustedError(absl::StrCat("options.lattice_n: ", r.lattice_n,
                                                     " exceeds this server's limit of ",
                                                     limits.max_lattice_n, " (--max_lattice_n)"));
  }
  // The lattice check's worst case, known from the options alone: every sampled tet of a result
  // at its tet budget. Checked here so that a call that could never run is answered before its
  // upload.
  const int64_t budget = o.send_max_tets ? r.max_tets : limits.max_output_tets;
  const int64_t sampled = r.lattice_max_tets == 0 ? budget : std::min(r.lattice_max_tets, budget);
  const int64_t per_tet = LatticePointsPerTet(r.lattice_n);
  if (r.lattice_n > 0 && sampled > limits.max_lattice_points / per_tet) {
    return absl::ResourceExhaustedError(
        absl::StrCat("options.lattice_n = ", r.lattice_n, " (", per_tet, " points a tet) on up to ",
                     sampled, " tets (lattice_max_tets = ", r.lattice_max_tets,
                     r.lattice_max_tets == 0 ? ": every tet, up to max_tets" : "", ") may sample ",
                     static_cast<double>(per_tet) * static_cast<double>(sampled),
                     " points, above this server's limit of ", limits.max_lattice_points,
                     " (--max_lattice_points); lower lattice_n, lattice_max_tets or max_tets"));
  }
  o.stream_every_iteration = in.stream_every_iteration();
  o.skip_final_mesh = in.skip_final_mesh();
  o.response_chunk_bytes = in.response_chunk_bytes();
  return o;
}

RefineOptions ToCoreOptions(const RequestOptions& o, const ServiceLimits& limits) {
  RefineOptions core = o.refine;
  if (!o.send_max_tets) core.max_tets = limits.max_output_tets;
  return core;
}

void IterationStatsToWire(const IterationStats& s, v1::IterationStats* out) {
  out->set_iteration(s.iteration);
  out->set_initial_tets(s.initial_tets);
  out->set_final_tets(s.final_tets);
  out->set_tets_with_error(s.tets_with_error);
  out->set_edges(s.edges);
  out->set_split_edges(s.split_edges);
  out->set_short_edges_kept(s.short_edges_kept);
  out->set_max_error(s.max_error);
  out->set_mean_error(s.mean_error);
  out->mutable_configuration_counts()->Assign(s.configurations.begin(), s.configurations.end());
  out->set_schonhardt_prisms(s.schonhardt_prisms);
  QualityToWire(s.quality, out->mutable_quality());
  out->set_seconds(s.seconds);
  out->set_max_segment_error(s.max_segment_error);
  out->set_closure_edges(s.closure_edges);
  out->set_guard_edges(s.guard_edges);
  out->set_other_tilings(s.other_tilings);
  out->set_failing_tets(s.failing_tets);
}

absl::StatusOr<IterationStats> IterationStatsFromWire(const v1::IterationStats& in) {
  if (in.configuration_counts_size() != kNumConfigurations) {
    return absl::DataLossError(absl::StrCat("iteration_stats.configuration_counts: expected ",
                                            kNumConfigurations, " entries, got ",
                                            in.configuration_counts_size()));
  }
  IterationStats s;
  s.iteration = in.iteration();
  s.initial_tets = in.initial_tets();
  s.final_tets = in.final_tets();
  s.tets_with_error = in.tets_with_error();
  s.edges = in.edges();
  s.split_edges = in.split_edges();
  s.short_edges_kept = in.short_edges_kept();
  s.max_error = in.max_error();
  s.mean_error = in.mean_error();
  for (int i = 0; i < kNumConfigurations; ++i) s.configurations[i] = in.configuration_counts(i);
  s.schonhardt_prisms = in.schonhardt_prisms();
  s.quality = QualityFromWire(in.quality());
  s.seconds = in.seconds();
  s.max_segment_error = in.max_segment_error();
  s.closure_edges = in.closure_edges();
  s.guard_edges = in.guard_edges();
  s.other_tilings = in.other_tilings();
  s.failing_tets = in.failing_tets();
  return s;
}

void SummaryToWire(const RefineResult& r, const ServiceSummary& service, int64_t input_tets,
                   v1::Summary* out) {
  out->set_stop_reason(StopReasonToWire(r.stop_reason));
  out->set_iterations(static_cast<int32_t>(r.iterations.size()));
  out->set_input_tets(input_tets);
  out->set_output_tets(static_cast<int64_t>(r.mesh.tets.size()));
  out->set_output_vertices(static_cast<int64_t>(r.mesh.points.size()));
  out->set_norm_coeff(r.norm_coeff);
  QualityToWire(r.initial_quality, out->mutable_initial_quality());
  QualityToWire(r.final_quality, out->mutable_final_quality());
  v1::LatticeStats* lattice = out->mutable_lattice();
  lattice->set_n(r.lattice.n);
  lattice->set_tets_sampled(r.lattice.tets_sampled);
  lattice->set_points_sampled(r.lattice.points_sampled);
  lattice->set_max_error(r.lattice.max_error);
  lattice->set_mean_error(r.lattice.mean_error);
  lattice->set_share_above_epsilon(r.lattice.share_above_epsilon);
  lattice->set_volume_mean_error(r.lattice.volume_mean_error);
  lattice->set_volume_share_above_epsilon(r.lattice.volume_share_above_epsilon);
  out->set_tets_reoriented(r.tets_reoriented);
  out->set_next_iteration_tets(r.next_iteration_tets);
  out->set_next_iteration_min_quality(r.next_iteration_min_quality);
  out->set_final_max_error(r.final_max_error);
  out->set_final_mean_error(r.final_mean_error);
  out->set_certified_max_error(r.certified_max_error);
  out->set_max_tets(service.max_tets);
  out->set_refine_seconds(r.seconds);
  out->set_input_seconds(service.input_seconds);
  out->set_total_seconds(service.total_seconds);
}

absl::Status SummaryFromWire(const v1::Summary& in, RefineResult* r, ServiceSummary* service) {
  absl::StatusOr<StopReason> reason = StopReasonFromWire(in.stop_reason());
  if (!reason.ok()) return reason.status();
  r->stop_reason = *reason;
  r->next_iteration_tets = in.next_iteration_tets();
  r->next_iteration_min_quality = in.next_iteration_min_quality();
  r->final_max_error = in.final_max_error();
  r->final_mean_error = in.final_mean_error();
  r->certified_max_error = in.certified_max_error();
  r->norm_coeff = in.norm_coeff();
  r->initial_quality = QualityFromWire(in.initial_quality());
  r->final_quality = QualityFromWire(in.final_quality());
  const v1::LatticeStats& lattice = in.lattice();
  r->lattice = LatticeStats{.n = lattice.n(),
                            .tets_sampled = lattice.tets_sampled(),
                            .points_sampled = lattice.points_sampled(),
                            .max_error = lattice.max_error(),
                            .mean_error = lattice.mean_error(),
                            .share_above_epsilon = lattice.share_above_epsilon(),
                            .volume_mean_error = lattice.volume_mean_error(),
                            .volume_share_above_epsilon = lattice.volume_share_above_epsilon()};
  r->tets_reoriented = in.tets_reoriented();
  r->seconds = in.refine_seconds();
  service->max_tets = in.max_tets();
  service->input_seconds = in.input_seconds();
  service->total_seconds = in.total_seconds();
  return absl::OkStatus();
}

void LimitsToWire(const ServiceLimits& limits, v1::ServerLimits* out) {
  out->set_max_voxels(limits.max_voxels);
  out->set_max_input_tets(limits.max_input_tets);
  out->set_max_output_tets(limits.max_output_tets);
  out->set_max_concurrent_refinements(limits.max_concurrent_refinements);
  out->set_max_message_bytes(limits.max_message_bytes);
  out->set_max_iterations(limits.max_iterations);
  out->set_max_lattice_n(limits.max_lattice_n);
  out->set_max_lattice_points(limits.max_lattice_points);
  out->set_max_call_seconds(limits.max_call_seconds);
  out->set_input_deadline_seconds(limits.input_deadline_seconds);
  out->set_idle_timeout_seconds(limits.idle_timeout_seconds);
  out->set_write_stall_seconds(limits.write_stall_seconds);
  out->set_queue_seconds(limits.queue_seconds);
  out->set_max_calls_per_identity(limits.max_calls_per_identity);
  out->set_memory_budget_bytes(limits.memory_budget_bytes);
  out->set_bytes_per_output_tet(limits.bytes_per_output_tet);
}

ServiceLimits LimitsFromWire(const v1::ServerLimits& in) {
  return ServiceLimits{.max_voxels = in.max_voxels(),
                       .max_input_tets = in.max_input_tets(),
                       .max_output_tets = in.max_output_tets(),
                       .max_concurrent_refinements = in.max_concurrent_refinements(),
                       .max_message_bytes = in.max_message_bytes(),
                       .max_iterations = in.max_iterations(),
                       .max_lattice_n = in.max_lattice_n(),
                       .max_lattice_points = in.max_lattice_points(),
                       .max_call_seconds = in.max_call_seconds(),
                       .input_deadline_seconds = in.input_deadline_seconds(),
                       .idle_timeout_seconds = in.idle_timeout_seconds(),
                       .write_stall_seconds = in.write_stall_seconds(),
                       .queue_seconds = in.queue_seconds(),
                       .max_calls_per_identity = in.max_calls_per_identity(),
                       .memory_budget_bytes = in.memory_budget_bytes(),
                       .bytes_per_output_tet = in.bytes_per_output_tet()};
}

size_t LabelWireBytes(const std::vector<int32_t>& labels) {
  size_t bytes = 1;
  for (int32_t label : labels) {
    bytes =
        std::max(bytes, google::protobuf::io::CodedOutputStream::VarintSize32SignExtended(label));
  }
  return bytes;
}

grpc::Status ToGrpcStatus(const absl::Status& status) {
  if (status.ok()) return grpc::Status::OK;
  return grpc::Status(static_cast<grpc::StatusCode>(status.code()), std::string(status.message()));
}

absl::Status FromGrpcStatus(const grpc::Status& status) {
  if (status.ok()) return absl::OkStatus();
  return absl::Status(static_cast<absl::StatusCode>(status.error_code()), status.error_message());
}

}  // namespace tetrefine::wire
