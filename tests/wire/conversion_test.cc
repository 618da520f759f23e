// Direct tests of wire/conversion.h: every one-message conversion round-trips core -> proto ->
// core unchanged, and every refusal names the field it refuses.

#include "wire/conversion.h"

#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <string>

#include "gmock/gmock.h"
#include "gtest/gtest.h"

namespace tetrefine::wire {
namespace {

using ::testing::HasSubstr;
using ::testing::StartsWith;

constexpr VoxelType kAllTypes[] = {VoxelType::kUint8, VoxelType::kInt16,   VoxelType::kUint16,
                                   VoxelType::kInt32, VoxelType::kFloat32, VoxelType::kFloat64};

TEST(WireConversion, VoxelTypeRoundTripsAndUnknownNamesTheField) {
  for (VoxelType type : kAllTypes) {
    absl::StatusOr<VoxelType> back = VoxelTypeFromWire(VoxelTypeToWire(type), "f");
    ASSERT_TRUE(back.ok()) << back.status();
    EXPECT_EQ(*back, type);
  }
  for (int bad : {int{v1::VOXEL_TYPE_UNSPECIFIED}, 99, -1}) {
    absl::StatusOr<VoxelType> back = VoxelTypeFromWire(bad, "volume_header.voxel_type");
    EXPECT_EQ(back.status().code(), absl::StatusCode::kInvalidArgument);
    EXPECT_THAT(std::string(back.status().message()), StartsWith("volume_header.voxel_type: "));
  }
}

// Random but valid request options, every optional field sometimes set.
RequestOptions RandomOptions(std::mt19937_64& rng) {
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  auto coin = [&] { return (rng() & 1) != 0; };
  RequestOptions o;
  RefineOptions& r = o.refine;
  r.epsilon = 1e-4 + unit(rng);
  r.max_iterations = static_cast<int>(rng() % 101);  // the default cap: 100
  if (coin()) o.SetMaxTets(1 + static_cast<int64_t>(rng() % 1'000'000));
  if (coin()) r.norm_coeff = 0.5 + 1000.0 * unit(rng);
  r.outside = coin() ? OutsidePolicy::kClamp : OutsidePolicy::kReject;
  r.orientation = coin() ? OrientationPolicy::kNormalize : OrientationPolicy::kReject;
  // Within the default caps: order 16 (969 points a tet) on at most 200 000 tets.
  r.lattice_n = static_cast<int>(rng() % 17);
  r.lattice_max_tets = 1 + static_cast<int64_t>(rng() % 200'000);
  r.lattice_seed = rng();
  if (coin()) r.min_edge_length = unit(rng);
  r.min_quality = 0.5 * unit(rng);
  if (coin()) r.quality_reference = 1.0 - unit(rng);
  r.scheme = coin() ? RefineScheme::kPaper : RefineScheme::kLongestEdge;
  r.certify = r.lattice_n >= 4 && coin();  // certify needs points inside the tets
  r.track_parents = coin();
  o.stream_every_iteration = coin();
  o.skip_final_mesh = coin();
  o.response_chunk_bytes = static_cast<uint32_t>(rng());
  return o;
}

void ExpectSameOptions(const RequestOptions& expected, const RequestOptions& actual) {
  const RefineOptions& e = expected.refine;
  const RefineOptions& a = actual.refine;
  EXPECT_EQ(std::bit_cast<uint64_t>(e.epsilon), std::bit_cast<uint64_t>(a.epsilon));
  EXPECT_EQ(e.max_iterations, a.max_iterations);
  EXPECT_EQ(expected.send_max_tets, actual.send_max_tets);
  if (expected.send_max_tets) {
    EXPECT_EQ(e.max_tets, a.max_tets);
  }
  EXPECT_EQ(e.norm_coeff, a.norm_coeff);
  EXPECT_EQ(e.outside, a.outside);
  EXPECT_EQ(e.orientation, a.orientation);
  EXPECT_EQ(e.lattice_n, a.lattice_n);
  EXPECT_EQ(e.lattice_max_tets, a.lattice_max_tets);
  EXPECT_EQ(e.lattice_seed, a.lattice_seed);
  EXPECT_EQ(e.min_edge_length, a.min_edge_length);
  EXPECT_EQ(e.quality_reference, a.quality_reference);
  ASSERT_EQ(e.min_quality.has_value(), a.min_quality.has_value());
  if (e.min_quality.has_value()) {
    EXPECT_EQ(std::bit_cast<uint64_t>(*e.min_quality), std::bit_cast<uint64_t>(*a.min_quality));
  }
  EXPECT_EQ(e.scheme, a.scheme);
  EXPECT_EQ(e.certify, a.certify);
  EXPECT_EQ(e.track_parents, a.track_parents);
  EXPECT_EQ(expected.stream_every_iteration, actual.stream_every_iteration);
  EXPECT_EQ(expected.skip_final_mesh, actual.skip_final_mesh);
  EXPECT_EQ(expected.response_chunk_bytes, actual.response_chunk_bytes);
}

TEST(WireConversion, RequestOptionsRoundTrip) {
  std::mt19937_64 rng(20261122);
  const ServiceLimits limits;
  for (int i = 0; i < 200; ++i) {
    const RequestOptions options = RandomOptions(rng);
    v1::RefineOptions message;
    RequestOptionsToWire(options, &message);
    // Through bytes too: what the client sends is what the server parses.
    v1::RefineOptions parsed;
    ASSERT_TRUE(parsed.ParseFromString(message.SerializeAsString()));
    absl::StatusOr<RequestOptions> back = RequestOptionsFromWire(parsed, limits);
    ASSERT_TRUE(back.ok()) << back.status();
    ExpectSameOptions(options, *back);
  }
}

TEST(WireConversion, EmptyOptionsMessageGivesTheCoreDefaults) {
  absl::StatusOr<RequestOptions> back = RequestOptionsFromWire(v1::RefineOptions{}, {});
  ASSERT_TRUE(back.ok()) << back.status();
  ExpectSameOptions(RequestOptions{}, *back);
  RequestOptions core_defaults;
  core_defaults.refine = RefineOptions{};
  ExpectSameOptions(core_defaults, *back);
}

// The wire refuses what the core refuses, with the core's words: one set of limits.
TEST(WireConversion, RefusesExactlyWhatTheCoreRefuses) {
  std::mt19937_64 rng(11);
  for (int i = 0; i < 300; ++i) {
    RequestOptions options = RandomOptions(rng);
    RefineOptions& r = options.refine;
    switch (rng() % 6) {  // one field pushed around its bound
      case 0:
        r.epsilon = static_cast<double>(static_cast<int>(rng() % 3) - 1);
        break;
      case 1:
        r.lattice_n = 62 + static_cast<int>(rng() % 5);
        break;
      case 2:
        r.min_quality = 0.5 * static_cast<double>(rng() % 4);
        break;
      case 3:
        r.max_iterations = static_cast<int>(rng() % 3) - 1;
        break;
      case 4:
        r.lattice_max_tets = static_cast<int64_t>(rng() % 3) - 1;
        break;
      case 5:
        r.min_edge_length = static_cast<double>(rng() % 3) - 1.0;
        break;
    }
    v1::RefineOptions message;
    RequestOptionsToWire(options, &message);
    const absl::Status core = ValidateRefineOptions(r);
    // The server's own work caps (max_lattice_n and friends) are not the core's limits: lifted
    // here so that only the core's bounds are compared.
    ServiceLimits uncapped;
    uncapped.max_iterations = std::numeric_limits<int>::max();
    uncapped.max_lattice_n = 64;
    uncapped.max_lattice_points = std::numeric_limits<int64_t>::max();
    const absl::Status wire = RequestOptionsFromWire(message, uncapped).status();
    EXPECT_EQ(wire, core) << message.ShortDebugString();
  }
}

TEST(WireConversion, CoreOptionsSurviveTheWire) {
  RefineOptions core;
  core.epsilon = 0.03;
  core.max_iterations = 7;
  core.max_tets = 12345;
  core.norm_coeff = 2.5;
  core.outside = OutsidePolicy::kClamp;
  core.orientation = OrientationPolicy::kNormalize;
  core.lattice_n = 4;
  core.lattice_max_tets = 99;
  core.lattice_seed = 42;
  core.min_edge_length = 0.25;
  core.min_quality = 0.01;
  core.quality_reference = 0.375;
  core.threads = 3;  // the server's business: not sent
  v1::RefineOptions message;
  const RequestOptions request = RequestOptionsFromCore(core);
  EXPECT_TRUE(request.send_max_tets);
  EXPECT_EQ(request.refine.threads, 0);
  RequestOptionsToWire(request, &message);
  const ServiceLimits limits;
  absl::StatusOr<RequestOptions> parsed = RequestOptionsFromWire(message, limits);
  ASSERT_TRUE(parsed.ok()) << parsed.status();
  const RefineOptions back = ToCoreOptions(*parsed, limits);
  EXPECT_EQ(back.epsilon, core.epsilon);
  EXPECT_EQ(back.max_iterations, core.max_iterations);
  EXPECT_EQ(back.max_tets, core.max_tets);
  EXPECT_EQ(back.norm_coeff, core.norm_coeff);
  EXPECT_EQ(back.outside, core.outside);
  EXPECT_EQ(back.orientation, core.orientation);
  EXPECT_EQ(back.lattice_n, core.lattice_n);
  EXPECT_EQ(back.lattice_max_tets, core.lattice_max_tets);
  EXPECT_EQ(back.lattice_seed, core.lattice_seed);
  EXPECT_EQ(back.min_edge_length, core.min_edge_length);
  EXPECT_EQ(back.min_quality, core.min_quality);
  EXPECT_EQ(back.quality_reference, core.quality_reference);
  EXPECT_EQ(back.threads, 0);
}

TEST(WireConversion, UnsetMaxTetsBecomesTheServersLimit) {
  ServiceLimits limits;
  limits.max_output_tets = 777;
  absl::StatusOr<RequestOptions> parsed = RequestOptionsFromWire(v1::RefineOptions{}, limits);
  ASSERT_TRUE(parsed.ok());
  EXPECT_EQ(ToCoreOptions(*parsed, limits).max_tets, 777);
}

// One bad field each: the error is INVALID_ARGUMENT and starts with "options.<field>".
struct BadOption {
  const char* field;
  void (*set)(v1::RefineOptions*);
};

const BadOption kBadOptions[] = {
    {"epsilon", [](v1::RefineOptions* o) { o->set_epsilon(0.0); }},
    {"epsilon", [](v1::RefineOptions* o) { o->set_epsilon(-1.0); }},
    {"epsilon", [](v1::RefineOptions* o) { o->set_epsilon(std::nan("")); }},
    {"epsilon",
     [](v1::RefineOptions* o) { o->set_epsilon(std::numeric_limits<double>::infinity()); }},
    {"max_iterations", [](v1::RefineOptions* o) { o->set_max_iterations(-1); }},
    {"max_tets", [](v1::RefineOptions* o) { o->set_max_tets(0); }},
    {"norm_coeff", [](v1::RefineOptions* o) { o->set_norm_coeff(0.0); }},
    {"norm_coeff", [](v1::RefineOptions* o) { o->set_norm_coeff(std::nan("")); }},
    {"outside_policy",
     [](v1::RefineOptions* o) { o->set_outside_policy(static_cast<v1::OutsidePolicy>(42)); }},
    {"orientation_policy",
     [](v1::RefineOptions* o) {
       o->set_orientation_policy(static_cast<v1::OrientationPolicy>(42));
     }},
    {"lattice_n", [](v1::RefineOptions* o) { o->set_lattice_n(-1); }},
    {"lattice_n", [](v1::RefineOptions* o) { o->set_lattice_n(65); }},
    {"lattice_max_tets", [](v1::RefineOptions* o) { o->set_lattice_max_tets(-1); }},
    {"min_edge_length", [](v1::RefineOptions* o) { o->set_min_edge_length(-0.5); }},
    {"min_quality", [](v1::RefineOptions* o) { o->set_min_quality(1.0); }},
    {"min_quality", [](v1::RefineOptions* o) { o->set_min_quality(-0.1); }},
    {"quality_reference", [](v1::RefineOptions* o) { o->set_quality_reference(0.0); }},
    {"quality_reference", [](v1::RefineOptions* o) { o->set_quality_reference(std::nan("")); }},
};

TEST(WireConversion, EachBadOptionIsRefusedNamingItsField) {
  for (const BadOption& bad : kBadOptions) {
    v1::RefineOptions message;
    bad.set(&message);
    absl::StatusOr<RequestOptions> parsed = RequestOptionsFromWire(message, {});
    EXPECT_EQ(parsed.status().code(), absl::StatusCode::kInvalidArgument) << bad.field;
    EXPECT_THAT(std::string(parsed.status().message()),
                StartsWith(std::string("options.") + bad.field))
        << message.ShortDebugString();
  }
}

TEST(WireConversion, MaxTetsAboveTheServersLimitIsResourceExhausted) {
  ServiceLimits limits;
  limits.max_output_tets = 1000;
  v1::RefineOptions message;
  message.set_max_tets(1000);
  EXPECT_TRUE(RequestOptionsFromWire(message, limits).ok());
  message.set_max_tets(1001);
  absl::StatusOr<RequestOptions> parsed = RequestOptionsFromWire(message, limits);
  EXPECT_EQ(parsed.status().code(), absl::StatusCode::kResourceExhausted);
  EXPECT_THAT(std::string(parsed.status().message()), StartsWith("options.max_tets: 1001"));
  EXPECT_THAT(std::string(parsed.status().message()), HasSubstr("1000"));
}

IterationStats RandomStats(std::mt19937_64& rng) {
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  IterationStats s;
  s.iteration = static_cast<int>(rng() % 50) + 1;
  s.initial_tets = static_cast<int64_t>(rng() >> 20);
  s.final_tets = static_cast<int64_t>(rng() >> 20);
  s.tets_with_error = static_cast<int64_t>(rng() >> 20);
  s.edges = static_cast<int64_t>(rng() >> 20);
  s.split_edges = static_cast<int64_t>(rng() >> 20);
  s.short_edges_kept = static_cast<int64_t>(rng() >> 20);
  s.max_error = unit(rng);
  s.mean_error = unit(rng);
  for (int64_t& c : s.configurations) c = static_cast<int64_t>(rng() >> 30);
  s.schonhardt_prisms = static_cast<int64_t>(rng() % 10);
  s.quality = QualityStats{.min = unit(rng), .mean = unit(rng), .count = 17};
  s.seconds = unit(rng);
  return s;
}

TEST(WireConversion, IterationStatsRoundTrip) {
  std::mt19937_64 rng(7);
  for (int i = 0; i < 100; ++i) {
    const IterationStats s = RandomStats(rng);
    v1::IterationStats message;
    IterationStatsToWire(s, &message);
    absl::StatusOr<IterationStats> back = IterationStatsFromWire(message);
    ASSERT_TRUE(back.ok()) << back.status();
    EXPECT_EQ(back->iteration, s.iteration);
    EXPECT_EQ(back->initial_tets, s.initial_tets);
    EXPECT_EQ(back->final_tets, s.final_tets);
    EXPECT_EQ(back->tets_with_error, s.tets_with_error);
    EXPECT_EQ(back->edges, s.edges);
    EXPECT_EQ(back->split_edges, s.split_edges);
    EXPECT_EQ(back->short_edges_kept, s.short_edges_kept);
    EXPECT_EQ(back->max_error, s.max_error);
    EXPECT_EQ(back->mean_error, s.mean_error);
    EXPECT_EQ(back->configurations, s.configurations);
    EXPECT_EQ(back->schonhardt_prisms, s.schonhardt_prisms);
    EXPECT_EQ(back->quality.min, s.quality.min);
    EXPECT_EQ(back->quality.mean, s.quality.mean);
    EXPECT_EQ(back->quality.count, s.quality.count);
    EXPECT_EQ(back->seconds, s.seconds);
  }
}

TEST(WireConversion, IterationStatsWithTheWrongConfigurationCountNamesTheField) {
  std::mt19937_64 rng(8);
  v1::IterationStats message;
  IterationStatsToWire(RandomStats(rng), &message);
  message.add_configuration_counts(1);
  absl::StatusOr<IterationStats> back = IterationStatsFromWire(message);
  EXPECT_EQ(back.status().code(), absl::StatusCode::kDataLoss);
  EXPECT_THAT(std::string(back.status().message()),
              StartsWith("iteration_stats.configuration_counts"));
}

TEST(WireConversion, SummaryRoundTripsEveryStopReason) {
  for (StopReason reason :
       {StopReason::kConverged, StopReason::kMaxIterations, StopReason::kTetBudget,
        StopReason::kCancelled, StopReason::kQualityFloor, StopReason::kMinEdgeLength}) {
    RefineResult r;
    r.mesh.points.resize(11);
    r.mesh.tets.resize(13);
    r.iterations.resize(3);
    r.stop_reason = reason;
    r.next_iteration_tets = 99;
    r.next_iteration_min_quality = 1e-7;
    r.norm_coeff = 3.5;
    r.initial_quality = {.min = 0.1, .mean = 0.5, .count = 4};
    r.final_quality = {.min = 0.2, .mean = 0.6, .count = 13};
    r.lattice = {.n = 8,
                 .tets_sampled = 13,
                 .points_sampled = 13 * 165,
                 .max_error = 0.3,
                 .mean_error = 0.01,
                 .share_above_epsilon = 0.02,
                 .volume_mean_error = 0.005,
                 .volume_share_above_epsilon = 0.001};
    r.final_max_error = 0.09;
    r.final_mean_error = 0.008;
    r.tets_reoriented = 2;
    r.seconds = 1.25;
    const ServiceSummary service{.max_tets = 500, .input_seconds = 0.5, .total_seconds = 2.0};
    v1::Summary message;
    SummaryToWire(r, service, 4, &message);
    EXPECT_EQ(message.iterations(), 3);
    EXPECT_EQ(message.input_tets(), 4);
    EXPECT_EQ(message.output_tets(), 13);
    EXPECT_EQ(message.output_vertices(), 11);

    RefineResult back;
    ServiceSummary back_service;
    ASSERT_TRUE(SummaryFromWire(message, &back, &back_service).ok());
    EXPECT_EQ(back.stop_reason, reason);
    EXPECT_EQ(back.next_iteration_tets, r.next_iteration_tets);
    EXPECT_EQ(back.next_iteration_min_quality, r.next_iteration_min_quality);
    EXPECT_EQ(back.norm_coeff, r.norm_coeff);
    EXPECT_EQ(back.initial_quality.mean, r.initial_quality.mean);
    EXPECT_EQ(back.final_quality.count, r.final_quality.count);
    EXPECT_EQ(back.lattice.points_sampled, r.lattice.points_sampled);
    EXPECT_EQ(back.lattice.volume_share_above_epsilon, r.lattice.volume_share_above_epsilon);
    EXPECT_EQ(back.final_max_error, r.final_max_error);
    EXPECT_EQ(back.final_mean_error, r.final_mean_error);
    EXPECT_EQ(back.tets_reoriented, r.tets_reoriented);
    EXPECT_EQ(back.seconds, r.seconds);
    EXPECT_EQ(back_service.max_tets, service.max_tets);
    EXPECT_EQ(back_service.input_seconds, service.input_seconds);
    EXPECT_EQ(back_service.total_seconds, service.total_seconds);
  }
}

TEST(WireConversion, UnknownStopReasonNamesTheField) {
  v1::Summary message;
  message.set_stop_reason(static_cast<v1::StopReason>(77));
  RefineResult r;
  ServiceSummary s;
  absl::Status status = SummaryFromWire(message, &r, &s);
  EXPECT_EQ(status.code(), absl::StatusCode::kDataLoss);
  EXPECT_THAT(std::string(status.message()), StartsWith("summary.stop_reason: unknown value 77"));
}

TEST(WireConversion, LimitsRoundTrip) {
  const ServiceLimits limits{.max_voxels = 1,
                             .max_input_tets = 2,
                             .max_output_tets = 3,
                             .max_concurrent_refinements = 4,
                             .max_message_bytes = 5};
  v1::ServerLimits message;
  LimitsToWire(limits, &message);
  const ServiceLimits back = LimitsFromWire(message);
  EXPECT_EQ(back.max_voxels, 1);
  EXPECT_EQ(back.max_input_tets, 2);
  EXPECT_EQ(back.max_output_tets, 3);
  EXPECT_EQ(back.max_concurrent_refinements, 4);
  EXPECT_EQ(back.max_message_bytes, 5);
}

TEST(WireConversion, StatusRoundTripsEveryCanonicalCode) {
  for (int code = 0; code <= 16; ++code) {
    const absl::Status status(static_cast<absl::StatusCode>(code), code == 0 ? "" : "why");
    const absl::Status back = FromGrpcStatus(ToGrpcStatus(status));
    EXPECT_EQ(back.code(), status.code());
    EXPECT_EQ(back.message(), status.message());
  }
}

}  // namespace
}  // namespace tetrefine::wire
