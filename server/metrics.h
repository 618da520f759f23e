#pragma once

// Prometheus metrics of the Refiner service and the HTTP endpoint that exposes them.

#include <cstdint>
#include <memory>
#include <string>

#include "absl/status/statusor.h"
#include "grpcpp/support/status.h"
#include "prometheus/counter.h"
#include "prometheus/exposer.h"
#include "prometheus/family.h"
#include "prometheus/gauge.h"
#include "prometheus/histogram.h"
#include "prometheus/registry.h"
#include "server/https_endpoint.h"

namespace tetrefine::server {

// What one finished Refine call contributes to the metrics.
struct CallMetrics {
  grpc::StatusCode code = grpc::StatusCode::OK;
  // false: refused on arrival, before any work (shutting down, authentication, the client's
  // quota of open calls, no memory for one more call)
  bool admitted = false;
  double seconds = 0.0;  // from arrival to status
  int64_t bytes_in = 0;
  int64_t tets_in = 0;
  int64_t tets_out = 0;
};

// The service's metrics in one registry. Thread-safe: every Refine call updates it.
class ServiceMetrics {
 public:
  ServiceMetrics();
  ServiceMetrics(const ServiceMetrics&) = delete;
  ServiceMetrics& operator=(const ServiceMetrics&) = delete;

  // Holds the in-flight gauge up for an admitted refinement's lifetime.
  class InFlight {
   public:
    explicit InFlight(ServiceMetrics* metrics);
    ~InFlight();
    InFlight(const InFlight&) = delete;
    InFlight& operator=(const InFlight&) = delete;

   private:
    ServiceMetrics* metrics_;
  };

  void RecordCall(const CallMetrics& call);
  // A GetServerInfo call finished with `code` (clients call it before Refine: a refused token or
  // certificate shows here and nowhere else).
  void RecordServerInfo(grpc::StatusCode code);

  // The Prometheus text exposition of every metric (what /metrics serves).
  std::string Scrape() const;

  const std::shared_ptr<prometheus::Registry>& registry() const { return registry_; }

 private:
  std::shared_ptr<prometheus::Registry> registry_;
  prometheus::Family<prometheus::Counter>& calls_;
  prometheus::Family<prometheus::Counter>& info_calls_;
  prometheus::Histogram& duration_;
  prometheus::Counter& tets_in_;
  prometheus::Counter& tets_out_;
  prometheus::Counter& bytes_in_;
  prometheus::Gauge& in_flight_;
};

// PEM files for serving /metrics over HTTPS; both empty: plain HTTP.
struct MetricsTls {
  std::string cert_file;  // certificate chain
  std::string key_file;   // its private key
  bool enabled() const { return !cert_file.empty(); }
};

// An HTTP server answering GET /metrics from `metrics` (prometheus-cpp's civetweb Exposer), or
// HTTPS (server/https_endpoint.h). Four connections at once, and a request that has not arrived
// whole within 5 s is dropped: a few clients that open connections and never finish a request
// cannot keep a scrape out.
class MetricsEndpoint {
 public:
  // `address` is host:port; port 0 picks a free port (see port()). UNAVAILABLE if it cannot bind
  // or (with `tls`) cannot load the certificate. One TLS endpoint per process.
  static absl::StatusOr<std::unique_ptr<MetricsEndpoint>> Start(
      const std::string& address, std::shared_ptr<ServiceMetrics> metrics,
      const MetricsTls& tls = {});

  // The port actually bound.
  int port() const { return port_; }

 private:
  MetricsEndpoint() = default;

  std::shared_ptr<ServiceMetrics> metrics_;       // outlives the endpoint that reads it
  std::unique_ptr<prometheus::Exposer> exposer_;  // plain HTTP
  std::unique_ptr<HttpsEndpoint> https_;          // HTTPS
  int port_ = 0;
};

}  // namespace tetrefine::server
