// tetrefine_server: the tetrefine.v1 Refiner service over the network.

#include <signal.h>
#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <fstream>
#include <memory>
#include <sstream>
#include <string>
#include <thread>

#include "absl/flags/parse.h"
#include "absl/flags/usage.h"
#include "absl/status/statusor.h"
#include "absl/strings/str_cat.h"
#include "absl/synchronization/mutex.h"
#include "grpcpp/grpcpp.h"
#include "grpcpp/security/server_credentials.h"
#include "server/memory_budget.h"
#include "server/metrics.h"
#include "server/refiner_service.h"
#include "server/server_flags.h"
#include "server/server_setup.h"
#include "server/shutdown_signals.h"
#include "server/tls_files.h"
#include "spdlog/sinks/stdout_color_sinks.h"
#include "spdlog/spdlog.h"

namespace tetrefine::server {
namespace {

absl::StatusOr<std::string> ReadFile(const std::string& path, const char* flag) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return absl::NotFoundError(absl::StrCat(flag, ": cannot read ", path));
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

absl::StatusOr<std::shared_ptr<grpc::ServerCredentials>> Credentials(const ServerSettings& s) {
  if (s.tls_cert.empty()) return grpc::InsecureServerCredentials();
  grpc::SslServerCredentialsOptions options;
  absl::StatusOr<std::string> cert_pem = ReadFile(s.tls_cert, "--tls_cert");
  if (!cert_pem.ok()) return cert_pem.status();
  absl::StatusOr<std::string> key_pem = ReadFile(s.tls_key, "--tls_key");
  if (!key_pem.ok()) return key_pem.status();
  std::string ca_text;
  if (!s.tls_client_ca.empty()) {
    absl::StatusOr<std::string> ca_pem = ReadFile(s.tls_client_ca, "--tls_client_ca");
    if (!ca_pem.ok()) return ca_pem.status();
    ca_text = *ca_pem;
  }
  if (absl::Status usable =
          CheckServerTlsFiles(*cert_pem, s.tls_cert, *key_pem, s.tls_key, ca_text, s.tls_client_ca);
      !usable.ok()) {
    return usable;
  }
  options.pem_key_cert_pairs.push_back({*key_pem, *cert_pem});
  if (!s.tls_client_ca.empty()) {
    options.pem_root_certs = ca_text;
    options.client_certificate_request = GRPC_SSL_REQUEST_AND_REQUIRE_CLIENT_CERTIFICATE_AND_VERIFY;
  }
  return grpc::SslServerCredentials(options);
}

// "0.0.0.0:0" with port 41234 bound -> "0.0.0.0:41234".
std::string BoundAddress(const std::string& listen, int port) {
  const size_t colon = listen.rfind(':');
  return absl::StrCat(colon == std::string::npos ? listen : listen.substr(0, colon), ":", port);
}

// Raises the soft limit on open files to the hard one. gRPC 1.51 stops accepting connections
// for good after one accept4 fails with EMFILE (a service sweep wedged a server under the common
// soft limit of 1024 with 1,100 idle connections; it stayed unreachable after they closed).
// Containers usually allow far more than their soft limit; what remains is bounded by the
// handshake timeout and the idle-connection limit (server_setup.cc).
void RaiseOpenFileLimit() {
  rlimit limit{};
  if (getrlimit(RLIMIT_NOFILE, &limit) != 0 || limit.rlim_cur >= limit.rlim_max) return;
  const rlim_t before = limit.rlim_cur;
  limit.rlim_cur = limit.rlim_max;
  if (setrlimit(RLIMIT_NOFILE, &limit) == 0) {
    spdlog::info("open file limit raised from {} to {}", before, limit.rlim_cur);
  }
}

int Run(ShutdownSignals& signals) {
  absl::StatusOr<ServerSettings> settings = SettingsFromFlags();
  if (!settings.ok()) {
    spdlog::error("{}", std::string(settings.status().message()));
    return 2;
  }
  const spdlog::level::level_enum level = spdlog::level::from_str(settings->log_level);
  // from_str maps every unknown name to "off": a typo must not silence the server.
  if (level == spdlog::level::off && settings->log_level != "off") {
    spdlog::error("unknown --log_level {}", settings->log_level);
    return 2;
  }
  spdlog::set_level(level);
  RaiseOpenFileLimit();
  // gRPC 1.51 locks Abseil mutexes for every stream, and Debian's Abseil runs its deadlock
  // detector on each lock: 8% of the server's CPU under a stream flood (perf, service sweep).
  // The detector only reports lock-order cycles; tetrefine's own locks are std::mutex.
  absl::SetMutexDeadlockDetectionMode(absl::OnDeadlockCycle::kIgnore);
  ServiceConfig& config = settings->service;
  const bool tls = !settings->tls_cert.empty();

  // Creating credentials initializes gRPC, which starts threads: the signals are blocked by now.
  absl::StatusOr<std::shared_ptr<grpc::ServerCredentials>> credentials = Credentials(*settings);
  if (!credentials.ok()) {
    spdlog::error("{}", std::string(credentials.status().message()));
    return 2;
  }
  if (config.access.tokens.has_value() && !tls) {
    spdlog::warn(
        "--token_file without --tls_cert: bearer tokens cross the network in plaintext; use TLS "
        "anywhere but a trusted network");
  }

  std::unique_ptr<MetricsEndpoint> metrics_endpoint;
  if (!settings->metrics_listen.empty()) {
    auto metrics = std::make_shared<ServiceMetrics>();
    absl::StatusOr<std::unique_ptr<MetricsEndpoint>> endpoint = MetricsEndpoint::Start(
        settings->metrics_listen, metrics,
        tls ? MetricsTls{.cert_file = settings->tls_cert, .key_file = settings->tls_key}
            : MetricsTls{});
    if (endpoint.ok()) {
      metrics_endpoint = *std::move(endpoint);
      config.metrics = std::move(metrics);
      spdlog::info("metrics on {}://{}/metrics", tls ? "https" : "http",
                   BoundAddress(settings->metrics_listen, metrics_endpoint->port()));
    } else {
      // Observability must not take the service down (e.g. a second server on one host with
      // the default port): refinements are served, the missing scrape target shows.
      spdlog::error("{}; serving without metrics", std::string(endpoint.status().message()));
    }
  }

  InitGrpcFeatures();  // before the builder exists
  RefinerService service(config);
  grpc::ServerBuilder builder;
  int port = 0, local_port = 0;
  builder.AddListeningPort(settings->listen, *credentials, &port);
  if (!settings->local_listen.empty()) {
    builder.AddListeningPort(settings->local_listen, grpc::InsecureServerCredentials(),
                             &local_port);
  }
  std::unique_ptr<grpc::Server> server = StartServer(config, &service, &builder, settings->server);
  if (server == nullptr || port == 0 || (!settings->local_listen.empty() && local_port == 0)) {
    spdlog::error(
        "cannot listen on {}{}: the port is in use (by another process, or by both listeners), "
        "the host is not this machine's{}",
        settings->listen, settings->local_listen.empty() ? "" : " and " + settings->local_listen,
        tls ? ", or the --tls_cert, --tls_key or --tls_client_ca PEM could not be loaded (gRPC's "
              "lines above say which)"
            : "");
    return 1;
  }
  const wire::ServiceLimits& l = config.limits;
  spdlog::info(
      "memory: limit {} ({}), budget for calls {}, {} bytes per output tet, max_output_tets {}, "
      "gRPC's own {}, one client's calls at most {} together",
      HumanBytes(settings->memory_limit_bytes), settings->memory_source,
      HumanBytes(l.memory_budget_bytes), l.bytes_per_output_tet, l.max_output_tets,
      HumanBytes(settings->server.grpc_memory_bytes), HumanBytes(config.max_bytes_per_identity));
  spdlog::info(
      "calls: max_concurrent {}, queue {} s, input deadline {} s, idle timeout {} s, write stall "
      "{} s, max {} s a call, {} open calls and {} slots per client; auth: {}{}",
      l.max_concurrent_refinements, l.queue_seconds, l.input_deadline_seconds,
      l.idle_timeout_seconds, l.write_stall_seconds, l.max_call_seconds, l.max_calls_per_identity,
      config.max_slots_per_identity,
      config.access.tokens.has_value()
          ? absl::StrCat(config.access.tokens->size(), " bearer tokens")
          : std::string("no tokens"),
      config.access.allowed_subjects.empty()
          ? std::string()
          : absl::StrCat(", ", config.access.allowed_subjects.size(), " allowed subjects"));
  if (local_port != 0) {
    spdlog::info("plaintext local listener on {}",
                 BoundAddress(settings->local_listen, local_port));
  }
  spdlog::info("tetrefine_server listening on {} (tls: {}, max_concurrent: {})",
               BoundAddress(settings->listen, port),
               tls ? (settings->tls_client_ca.empty() ? "on" : "mutual") : "off",
               l.max_concurrent_refinements);

  if (settings->exit_when_stdin_closes) {
    // A parent that is killed (SIGKILL, or SIGTERM to a Python pipeline) cannot stop its server:
    // LocalServer's servers outlived their pipelines, each holding a port and its memory (an
    // outside review, 2026-11-29). The kernel closes the parent's end of the pipe whatever
    // ended it; the end of input then drains the server as SIGTERM does.
    std::thread([] {
      char buffer[256];
      while (true) {
        const ssize_t n = ::read(STDIN_FILENO, buffer, sizeof(buffer));
        if (n == 0 || (n < 0 && errno != EINTR)) break;
      }
      spdlog::info("standard input closed (--exit_when_stdin_closes): draining");
      ::kill(::getpid(), SIGTERM);
    }).detach();
  }
  const int signal_number = signals.Wait();
  const double drain = settings->drain_seconds;
  const auto deadline = std::chrono::system_clock::now() +
                        std::chrono::duration_cast<std::chrono::system_clock::duration>(
                            std::chrono::duration<double>(drain));
  signals.SetDrainDeadline(deadline);
  // Load balancers and readiness probes asking about the Refiner stop sending work before the
  // listener goes away. The server as a whole ("", what liveness probes ask) stays SERVING
  // while it drains: a failing liveness probe would have the orchestrator kill the process in
  // the middle of the drain it is waiting for.
  server->GetHealthCheckService()->SetServingStatus(v1::Refiner::service_full_name(), false);
  // gRPC's Shutdown closes each connection as soon as its last call ends, which can cut off the
  // end of a response its client is still reading (the client sees UNAVAILABLE "Broken pipe"
  // for a call the server completed). So new calls are refused first, in-flight ones finish
  // with every connection open, their clients get a moment to read the rest, and only then
  // does gRPC shut down (cancelling whatever still runs at the deadline).
  service.StopAdmitting();
  // Logged once it is true: a health check made after this line must see NOT_SERVING (the
  // abuse test read SERVING once, under load, when the line came first).
  spdlog::info("signal {}: not serving, draining in-flight calls for up to {} s", signal_number,
               drain);
  const auto steady_deadline = std::chrono::steady_clock::now() +
                               std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                                   std::chrono::duration<double>(drain));
  service.WaitUntilIdle(steady_deadline);
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
  // First of all, before anything can start a thread.
  tetrefine::server::ShutdownSignals::BlockInThisThread();
  // Logs, errors included, go to stderr: stdout stays free for what a caller might parse.
  spdlog::set_default_logger(std::make_shared<spdlog::logger>(
      "", std::make_shared<spdlog::sinks::stderr_color_sink_mt>()));
  absl::SetProgramUsageMessage(
      "Serves tetrefine.v1.Refiner: tetrahedral mesh refinement.\n"
      "Usage: tetrefine_server [--flag=value ...]; every flag is listed below.");
  tetrefine::server::ConfigureUsage();
  absl::ParseCommandLine(argc, argv);
  // Lives until the process exits: its thread takes every later signal.
  auto* signals = new tetrefine::server::ShutdownSignals();
  return tetrefine::server::Run(*signals);
}
