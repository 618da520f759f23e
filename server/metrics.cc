#include "server/metrics.h"

#include <exception>
#include <string>
#include <utility>
#include <vector>

#include "absl/status/status.h"
#include "absl/strings/str_cat.h"
#include "prometheus/text_serializer.h"

namespace tetrefine::server {
namespace {

// Refinements take from milliseconds (a small mesh) to minutes (tens of millions of tets).
const prometheus::Histogram::BucketBoundaries& DurationBuckets() {
  static const auto* buckets = new prometheus::Histogram::BucketBoundaries{
      0.005, 0.01, 0.025, 0.05, 0.1, 0.25, 0.5, 1.0, 2.5, 5.0, 10.0, 30.0, 60.0, 120.0, 300.0};
  return *buckets;
}

// Both endpoints: four connections served at once, a request not whole within 5 s dropped.
constexpr int kWorkers = 4;
constexpr int kRequestTimeoutMs = 5000;

std::string CodeName(grpc::StatusCode code) {
  // gRPC and Abseil share the canonical codes and their names (OK, UNAVAILABLE, ...).
  return absl::StatusCodeToString(static_cast<absl::StatusCode>(code));
}

}  // namespace

ServiceMetrics::ServiceMetrics()
    : registry_(std::make_shared<prometheus::Registry>()),
      calls_(prometheus::BuildCounter()
                 .Name("tetrefine_refine_calls_total")
                 .Help("Refine calls finished, by gRPC status code")
                 .Register(*registry_)),
      info_calls_(prometheus::BuildCounter()
                      .Name("tetrefine_server_info_calls_total")
                      .Help("GetServerInfo calls, by gRPC status code (clients ask it first: a "
                            "refused token or certificate counts here)")
                      .Register(*registry_)),
      duration_(prometheus::BuildHistogram()
                    .Name("tetrefine_refine_duration_seconds")
                    .Help("Wall time of admitted Refine calls, from arrival to status")
                    .Register(*registry_)
                    .Add({}, DurationBuckets())),
      tets_in_(prometheus::BuildCounter()
                   .Name("tetrefine_tets_in_total")
                   .Help("Input tets of Refine calls whose input was read completely")
                   .Register(*registry_)
                   .Add({})),
      tets_out_(prometheus::BuildCounter()
                    .Name("tetrefine_tets_out_total")
                    .Help("Tets of the refined meshes of Refine calls that succeeded")
                    .Register(*registry_)
                    .Add({})),
      bytes_in_(prometheus::BuildCounter()
                    .Name("tetrefine_received_bytes_total")
                    .Help("Serialized bytes of Refine request messages received")
                    .Register(*registry_)
                    .Add({})),
      in_flight_(prometheus::BuildGauge()
                     .Name("tetrefine_refinements_in_flight")
                     .Help("Refine calls admitted and not yet finished")
                     .Register(*registry_)
                     .Add({})) {
  // Present from the start, so a dashboard's rate() has a series before the first call.
  calls_.Add({{"code", CodeName(grpc::StatusCode::OK)}});
  info_calls_.Add({{"code", CodeName(grpc::StatusCode::OK)}});
}

void ServiceMetrics::RecordServerInfo(grpc::StatusCode code) {
  info_calls_.Add({{"code", CodeName(code)}}).Increment();
}

ServiceMetrics::InFlight::InFlight(ServiceMetrics* metrics) : metrics_(metrics) {
  if (metrics_ != nullptr) metrics_->in_flight_.Increment();
}

ServiceMetrics::InFlight::~InFlight() {
  if (metrics_ != nullptr) metrics_->in_flight_.Decrement();
}

void ServiceMetrics::RecordCall(const CallMetrics& call) {
  calls_.Add({{"code", CodeName(call.code)}}).Increment();
  if (call.admitted) duration_.Observe(call.seconds);
  tets_in_.Increment(static_cast<double>(call.tets_in));
  tets_out_.Increment(static_cast<double>(call.tets_out));
  bytes_in_.Increment(static_cast<double>(call.bytes_in));
}

std::string ServiceMetrics::Scrape() const {
  return prometheus::TextSerializer().Serialize(registry_->Collect());
}

absl::StatusOr<std::unique_ptr<MetricsEndpoint>> MetricsEndpoint::Start(
    const std::string& address, std::shared_ptr<ServiceMetrics> metrics, const MetricsTls& tls) {
  std::unique_ptr<MetricsEndpoint> endpoint(new MetricsEndpoint());
  endpoint->metrics_ = std::move(metrics);
  if (tls.enabled()) {
    const std::shared_ptr<ServiceMetrics> served = endpoint->metrics_;
    absl::StatusOr<std::unique_ptr<HttpsEndpoint>> https = HttpsEndpoint::Start(
        address, tls.cert_file, tls.key_file, "/metrics", [served] { return served->Scrape(); },
        kWorkers, kRequestTimeoutMs);
    if (!https.ok()) {
      return absl::UnavailableError(absl::StrCat("cannot serve metrics (https) on ", address, ": ",
                                                 https.status().message()));
    }
    endpoint->https_ = *std::move(https);
    endpoint->port_ = endpoint->https_->port();
    return endpoint;
  }
  // civetweb's defaults wait 30 s for a request's headers, with the two threads prometheus-cpp
  // asks for: two unfinished requests kept every scrape out. Now one client needs four
  // connections held open for 5 s at a time to delay a scrape by that much.
  const std::vector<std::string> options = {
      "listening_ports",    address,
      "num_threads",        std::to_string(kWorkers),
      "request_timeout_ms", std::to_string(kRequestTimeoutMs)};
  try {
    // civetweb reports a bind failure by throwing.
    endpoint->exposer_ = std::make_unique<prometheus::Exposer>(options);
  } catch (const std::exception& e) {
    return absl::UnavailableError(
        absl::StrCat("cannot serve metrics on ", address, ": ", e.what()));
  }
  endpoint->exposer_->RegisterCollectable(endpoint->metrics_->registry());
  const std::vector<int> ports = endpoint->exposer_->GetListeningPorts();
  if (ports.empty() || ports.front() <= 0) {
    return absl::UnavailableError(absl::StrCat("metrics endpoint on ", address, " bound no port"));
  }
  endpoint->port_ = ports.front();
  return endpoint;
}

}  // namespace tetrefine::server
