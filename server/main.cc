// tetrefine_server: the tetrefine.v1 Refiner service over the network.

#include <pthread.h>
#include <signal.h>

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <fstream>
#include <memory>
#include <sstream>
#include <string>
#include <thread>

#include "absl/flags/flag.h"
#include "absl/flags/parse.h"
#include "absl/flags/usage.h"
#include "absl/status/statusor.h"
#include "absl/strings/str_cat.h"
#include "grpcpp/grpcpp.h"
#include "grpcpp/security/server_credentials.h"
#include "server/metrics.h"
#include "server/refiner_service.h"
#include "server/server_setup.h"
#include "spdlog/spdlog.h"

ABSL_FLAG(std::string, listen, "0.0.0.0:50051", "Address to listen on, host:port (port 0: any)");
ABSL_FLAG(std::string, metrics_listen, "0.0.0.0:9464",
          "Prometheus /metrics HTTP endpoint, host:port (port 0: any; empty: off). If it cannot "
          "be bound the server logs an error and serves without metrics");
ABSL_FLAG(int, threads, 0, "Core worker threads per refinement (0: all cores)");
ABSL_FLAG(int64_t, max_voxels, tetrefine::wire::ServiceLimits{}.max_voxels,
          "Largest volume (slab) accepted, in voxels");
ABSL_FLAG(int64_t, max_input_tets, tetrefine::wire::ServiceLimits{}.max_input_tets,
          "Largest input mesh accepted, in tets (vertices: 4 times this)");
ABSL_FLAG(int64_t, max_output_tets, tetrefine::wire::ServiceLimits{}.max_output_tets,
          "Tet budget of a refinement: the default and largest max_tets");
ABSL_FLAG(int, max_concurrent, tetrefine::wire::ServiceLimits{}.max_concurrent_refinements,
          "Refinements run at once; more are RESOURCE_EXHAUSTED");
ABSL_FLAG(int64_t, max_message_bytes, tetrefine::wire::ServiceLimits{}.max_message_bytes,
          "Largest request message accepted, in bytes");
ABSL_FLAG(double, drain_seconds, 30.0,
          "On SIGTERM/SIGINT, seconds in-flight calls may take to finish before being cancelled");
ABSL_FLAG(std::string, log_level, "info", "spdlog level: trace, debug, info, warn, error, off");
ABSL_FLAG(std::string, tls_cert, "", "PEM server certificate chain (enables TLS, with --tls_key)");
ABSL_FLAG(std::string, tls_key, "", "PEM private key of --tls_cert");
ABSL_FLAG(std::string, tls_client_ca, "",
          "PEM CA bundle: when set, clients must present a certificate it verifies");

namespace tetrefine::server {
namespace {

absl::StatusOr<std::string> ReadFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return absl::NotFoundError(absl::StrCat("cannot read ", path));
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

absl::StatusOr<std::shared_ptr<grpc::ServerCredentials>> Credentials() {
  const std::string cert = absl::GetFlag(FLAGS_tls_cert);
  const std::string key = absl::GetFlag(FLAGS_tls_key);
  const std::string client_ca = absl::GetFlag(FLAGS_tls_client_ca);
  if (cert.empty() && key.empty()) {
    if (!client_ca.empty()) {
      return absl::InvalidArgumentError("--tls_client_ca needs --tls_cert and --tls_key");
    }
    return grpc::InsecureServerCredentials();
  }
  if (cert.empty() || key.empty()) {
    return absl::InvalidArgumentError("--tls_cert and --tls_key go together");
  }
  grpc::SslServerCredentialsOptions options;
  absl::StatusOr<std::string> cert_pem = ReadFile(cert);
  if (!cert_pem.ok()) return cert_pem.status();
  absl::StatusOr<std::string> key_pem = ReadFile(key);
  if (!key_pem.ok()) return key_pem.status();
  options.pem_key_cert_pairs.push_back({*key_pem, *cert_pem});
  if (!client_ca.empty()) {
    absl::StatusOr<std::string> ca_pem = ReadFile(client_ca);
    if (!ca_pem.ok()) return ca_pem.status();
    options.pem_root_certs = *ca_pem;
    options.client_certificate_request = GRPC_SSL_REQUEST_AND_REQUIRE_CLIENT_CERTIFICATE_AND_VERIFY;
  }
  return grpc::SslServerCredentials(options);
}

ServiceConfig ConfigFromFlags() {
  ServiceConfig config;
  config.refine_threads = absl::GetFlag(FLAGS_threads);
  config.limits.max_voxels = absl::GetFlag(FLAGS_max_voxels);
  config.limits.max_input_tets = absl::GetFlag(FLAGS_max_input_tets);
  config.limits.max_output_tets = absl::GetFlag(FLAGS_max_output_tets);
  config.limits.max_concurrent_refinements = absl::GetFlag(FLAGS_max_concurrent);
  config.limits.max_message_bytes = absl::GetFlag(FLAGS_max_message_bytes);
  return config;
}

// "0.0.0.0:0" with port 41234 bound -> "0.0.0.0:41234".
std::string BoundAddress(const std::string& listen, int port) {
  const size_t colon = listen.rfind(':');
  return absl::StrCat(colon == std::string::npos ? listen : listen.substr(0, colon), ":", port);
}

int Run() {
  const std::string level_name = absl::GetFlag(FLAGS_log_level);
  const spdlog::level::level_enum level = spdlog::level::from_str(level_name);
  // from_str maps every unknown name to "off": a typo must not silence the server.
  if (level == spdlog::level::off && level_name != "off") {
    spdlog::error("unknown --log_level {}", level_name);
    return 2;
  }
  spdlog::set_level(level);

  ServiceConfig config = ConfigFromFlags();
  if (config.limits.max_concurrent_refinements < 1 || config.limits.max_voxels < 1 ||
      config.limits.max_input_tets < 1 || config.limits.max_output_tets < 1 ||
      config.limits.max_message_bytes < 1 || config.refine_threads < 0) {
    spdlog::error("limits must be >= 1 and --threads >= 0");
    return 2;
  }
  absl::StatusOr<std::shared_ptr<grpc::ServerCredentials>> credentials = Credentials();
  if (!credentials.ok()) {
    spdlog::error("{}", credentials.status().ToString());
    return 2;
  }

  // Handled synchronously by sigwait below. Blocked before gRPC starts its threads, which
  // inherit the mask, so no other thread can take the signal.
  sigset_t signals;
  sigemptyset(&signals);
  sigaddset(&signals, SIGINT);
  sigaddset(&signals, SIGTERM);
  pthread_sigmask(SIG_BLOCK, &signals, nullptr);

  std::unique_ptr<MetricsEndpoint> metrics_endpoint;
  if (const std::string metrics_listen = absl::GetFlag(FLAGS_metrics_listen);
      !metrics_listen.empty()) {
    auto metrics = std::make_shared<ServiceMetrics>();
    absl::StatusOr<std::unique_ptr<MetricsEndpoint>> endpoint =
        MetricsEndpoint::Start(metrics_listen, metrics);
    if (endpoint.ok()) {
      metrics_endpoint = *std::move(endpoint);
      config.metrics = std::move(metrics);
      spdlog::info("metrics on http://{}/metrics",
                   BoundAddress(metrics_listen, metrics_endpoint->port()));
    } else {
      // Observability must not take the service down (e.g. a second server on one host with
      // the default port): refinements are served, the missing scrape target shows.
      spdlog::error("{}; serving without metrics", endpoint.status().ToString());
    }
  }

  InitGrpcFeatures();  // before the builder exists
  RefinerService service(config);
  grpc::ServerBuilder builder;
  int port = 0;
  const std::string listen = absl::GetFlag(FLAGS_listen);
  builder.AddListeningPort(listen, *credentials, &port);
  std::unique_ptr<grpc::Server> server = StartServer(config, &service, &builder);
  if (server == nullptr || port == 0) {
    spdlog::error("cannot listen on {}", listen);
    return 1;
  }
  spdlog::info("tetrefine_server listening on {} (tls: {}, max_concurrent: {})",
               BoundAddress(listen, port), absl::GetFlag(FLAGS_tls_cert).empty() ? "off" : "on",
               config.limits.max_concurrent_refinements);

  int signal_number = 0;
  sigwait(&signals, &signal_number);
  const double drain = absl::GetFlag(FLAGS_drain_seconds);
  spdlog::info("signal {}: not serving, draining in-flight calls for up to {} s", signal_number,
               drain);
  // Load balancers probing health stop sending work before the listener goes away.
  server->GetHealthCheckService()->SetServingStatus(false);
  const auto deadline = std::chrono::system_clock::now() +
                        std::chrono::duration_cast<std::chrono::system_clock::duration>(
                            std::chrono::duration<double>(drain));
  // gRPC's Shutdown closes each connection as soon as its last call ends, which can cut off the
  // end of a response its client is still reading (the client sees UNAVAILABLE "Broken pipe"
  // for a call the server completed). So new calls are refused first, in-flight ones finish
  // with every connection open, their clients get a moment to read the rest, and only then
  // does gRPC shut down (cancelling whatever still runs at the deadline).
  service.StopAdmitting();
  while (service.active_refinements() > 0 && std::chrono::system_clock::now() < deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  std::this_thread::sleep_until(
      std::min(deadline, std::chrono::system_clock::now() + std::chrono::milliseconds(500)));
  server->Shutdown(deadline);
  server->Wait();
  // Stopping civetweb waits out its 2 s poll quantum; the process is exiting, so the kernel
  // closes the metrics socket at once instead.
  static_cast<void>(metrics_endpoint.release());
  spdlog::info("tetrefine_server stopped");
  return 0;
}

}  // namespace
}  // namespace tetrefine::server

int main(int argc, char** argv) {
  absl::SetProgramUsageMessage("Serves tetrefine.v1.Refiner: tetrahedral mesh refinement.");
  absl::ParseCommandLine(argc, argv);
  return tetrefine::server::Run();
}
