#include "server/server_flags.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>
#include <tuple>
#include <vector>

#include "absl/flags/flag.h"
#include "absl/flags/usage_config.h"
#include "absl/strings/ascii.h"
#include "absl/strings/match.h"
#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_split.h"
#include "absl/strings/strip.h"
#include "server/memory_budget.h"

namespace {
const tetrefine::wire::ServiceLimits kDefaults;
// Fewest output tets a call must be able to make for the server to start: below it the memory
// budget is a misconfiguration (a few MiB), not a small server.
constexpr int64_t kMinOutputTets = 10'000;
}  // namespace

// --- network -------------------------------------------------------------------------------
ABSL_FLAG(std::string, listen, "0.0.0.0:50051", "Address to listen on, host:port (port 0: any)");
ABSL_FLAG(std::string, local_listen, "",
          "A second, plaintext gRPC listener on a loopback address (127.0.0.1:PORT or [::1]:PORT; "
          "empty: none), for health probes run inside the container when --listen uses TLS. "
          "Tokens, quotas and limits apply there too; with --tls_client_ca it serves health "
          "checks only (Refine needs a client certificate)");
ABSL_FLAG(std::string, metrics_listen, "127.0.0.1:9464",
          "Prometheus /metrics endpoint, host:port (port 0: any; empty: off). HTTPS with the "
          "--tls_cert certificate when gRPC uses TLS. If it cannot be bound the server logs an "
          "error and serves without metrics");
ABSL_FLAG(double, keepalive_seconds, 60,
          "Ping a connection idle this long; drop it when the ping is not answered within "
          "--keepalive_timeout_seconds");
ABSL_FLAG(double, keepalive_timeout_seconds, 20, "See --keepalive_seconds");
ABSL_FLAG(double, max_connection_idle_seconds, 300,
          "Close a connection that has had no call for this long");
ABSL_FLAG(bool, reflection, true, "Serve gRPC server reflection (what grpcurl uses)");
ABSL_FLAG(bool, exit_when_stdin_closes, false,
          "Drain and exit, as on SIGTERM, when standard input reaches its end: for a parent "
          "process that keeps a pipe to it open, so that the server ends with the parent even "
          "when the parent is killed");
ABSL_FLAG(int, max_streams_per_connection, 100,
          "Streams (calls) one connection may have open at once; a client's next waits for one "
          "to end");
ABSL_FLAG(int, max_health_and_reflection_streams, 1000,
          "Health Watch and reflection streams the server keeps open at once, over all clients "
          "(they need no token); one more is cancelled as it arrives");
ABSL_FLAG(int64_t, grpc_memory_bytes, 0,
          "Memory gRPC itself may use for connections and streams (a gRPC resource quota; "
          "beyond it gRPC refuses new streams); 0: what the memory budget leaves of the memory "
          "limit, at least 64 MiB");
ABSL_FLAG(double, handshake_timeout_seconds, 20,
          "Close a new connection that has not completed its handshake (HTTP/2 preface, TLS) "
          "within this");

// --- TLS and identity ------------------------------------------------------------------------
ABSL_FLAG(std::string, tls_cert, "", "PEM server certificate chain (enables TLS, with --tls_key)");
ABSL_FLAG(std::string, tls_key, "", "PEM private key of --tls_cert");
ABSL_FLAG(std::string, tls_client_ca, "",
          "PEM CA bundle: when set, clients must present a certificate it verifies (on every "
          "listener); quotas then count per certificate common name");
ABSL_FLAG(std::string, tls_allowed_subjects, "",
          "Semicolon-separated client certificate common names or full subjects (e.g. "
          "CN=a,O=b, attributes in any order) allowed to call; empty: any certificate "
          "--tls_client_ca verifies");
ABSL_FLAG(std::string, token_file, "",
          "File of lines '<identity> <token>': every Refine and GetServerInfo call must carry "
          "metadata 'authorization: Bearer <token>'; quotas then count per identity");

// --- work and its limits ---------------------------------------------------------------------
ABSL_FLAG(int, threads, 0, "Core worker threads per refinement (0: all cores)");
ABSL_FLAG(int, max_concurrent, kDefaults.max_concurrent_refinements,
          "Refinements running at once; a call whose input is complete waits up to "
          "--queue_seconds for one of them");
ABSL_FLAG(int64_t, max_voxels, kDefaults.max_voxels, "Largest volume (slab) accepted, in voxels");
ABSL_FLAG(int64_t, max_input_tets, kDefaults.max_input_tets,
          "Largest input mesh accepted, in tets (vertices: 4 times this)");
ABSL_FLAG(int64_t, max_output_tets, 0,
          "Tet budget of a refinement: the default and largest max_tets (0: 50000000, or less "
          "when --max_concurrent calls of that many tets at --bytes_per_output_tet would not "
          "fit 90% of the memory budget together). A value that one call could not fit in the "
          "memory budget is refused");
ABSL_FLAG(int64_t, max_message_bytes, kDefaults.max_message_bytes,
          "Largest request message accepted, in bytes (GetServerInfo tells clients)");
ABSL_FLAG(int, max_iterations, kDefaults.max_iterations, "Largest max_iterations of a call");
ABSL_FLAG(int, max_lattice_n, kDefaults.max_lattice_n,
          "Largest lattice_n (order of the final lattice check) of a call, at most 64");
ABSL_FLAG(int64_t, max_lattice_points, kDefaults.max_lattice_points,
          "Most lattice points a call's final check may sample: points per tet x "
          "lattice_max_tets (or x max_tets when lattice_max_tets = 0)");
ABSL_FLAG(double, max_call_seconds, 600,
          "Wall time of a whole Refine call (input, wait, refinement, output); then "
          "DEADLINE_EXCEEDED");
ABSL_FLAG(double, input_deadline_seconds, 300,
          "A call's input must be complete (end_of_input, stream closed) this long after it began");
ABSL_FLAG(double, idle_timeout_seconds, 30,
          "Longest pause between a call's request messages, and after end_of_input until the "
          "client closes the stream");
ABSL_FLAG(double, write_stall_seconds, 60,
          "Longest wait for a client to take a response message; then its call is cancelled and "
          "what it holds is freed");
ABSL_FLAG(double, queue_seconds, 10,
          "Longest wait of a complete input for a refinement slot and memory; then "
          "RESOURCE_EXHAUSTED saying which was missing");
ABSL_FLAG(int, max_calls_per_identity, 16,
          "Open Refine calls of one client (its token identity, certificate common name, or "
          "else address); more are RESOURCE_EXHAUSTED. 0: no limit");
ABSL_FLAG(int, max_slots_per_identity, 0,
          "Refinement slots one client holds at once (0: --max_concurrent less one, at least 1), "
          "and a freed slot goes to the waiting client that holds the fewest: one client cannot "
          "take every slot");
ABSL_FLAG(int64_t, memory_limit_bytes, 0,
          "Memory this server may use in all (0: the cgroup limit, memory.max or "
          "memory.limit_in_bytes, else the machine's physical memory; or what ulimit -v / -d "
          "leaves of the address space at start, when that is less)");
ABSL_FLAG(int64_t, memory_budget_bytes, 0,
          "Memory the calls may reserve (0: the limit less max(256 MiB, 10%)). A call reserves "
          "2 x --max_message_bytes when it opens, its declared input as it arrives, and its "
          "output at its tet budget x --bytes_per_output_tet before it refines");
ABSL_FLAG(int64_t, bytes_per_output_tet, tetrefine::server::kDefaultBytesPerOutputTet,
          "Peak bytes of a refinement per tet of its budget (measured: 77-92; 160 leaves room "
          "for fragmentation)");

// --- process ---------------------------------------------------------------------------------
ABSL_FLAG(
    double, drain_seconds, 30.0,
    "On SIGTERM/SIGINT/SIGHUP, seconds in-flight calls may take to finish before being cancelled; "
    "later signals during the drain are logged and ignored");
ABSL_FLAG(std::string, log_level, "info",
          "spdlog level: trace, debug, info, warn, error, off (logs go to stderr)");

namespace tetrefine::server {
namespace {

absl::Status Invalid(const std::string& message) { return absl::InvalidArgumentError(message); }

bool IsLoopback(const std::string& address) {
  return absl::StartsWith(address, "127.") || absl::StartsWith(address, "[::1]:") ||
         absl::StartsWith(address, "localhost:");
}

bool Positive(double seconds) { return std::isfinite(seconds) && seconds > 0; }

// The longest duration a flag takes: about 31 years. gRPC's and the standard library's clocks
// count nanoseconds in 64 bits, so about 9.2e9 s overflows and the deadline lands in the past:
// every call failed at once with DEADLINE_EXCEEDED (found by an operator sweep, with 1e10 meant
// as "no limit").
constexpr double kMaxSeconds = 1e9;

absl::Status CheckSeconds(const char* name, double value, bool zero_allowed) {
  const bool in_range =
      std::isfinite(value) && (zero_allowed ? value >= 0 : value > 0) && value <= kMaxSeconds;
  if (in_range) return absl::OkStatus();
  return Invalid(absl::StrCat("--", name, ": must be ", zero_allowed ? ">= 0" : "> 0",
                              " and at most 1e9 s (31 years), got ", value));
}

// host:port with a port 0-65535 ("[v6]:port" for IPv6). gRPC took 127.0.0.1:99999 as port
// 34463, and a bare port for metrics bound every interface.
absl::Status CheckListenAddress(const char* name, const std::string& address) {
  absl::string_view port;
  bool has_host = false;
  if (absl::StartsWith(address, "[")) {
    const size_t close = address.find("]:");
    if (close != std::string::npos) {
      has_host = close > 1;
      port = absl::string_view(address).substr(close + 2);
    }
  } else if (const size_t colon = address.find(':');
             colon != std::string::npos && address.find(':', colon + 1) == std::string::npos) {
    has_host = colon > 0;
    port = absl::string_view(address).substr(colon + 1);
  }
  int number = -1;
  if (!has_host || port.empty() || port.size() > 5 ||
      !std::all_of(port.begin(), port.end(), absl::ascii_isdigit) ||
      !absl::SimpleAtoi(port, &number) || number > 65535) {
    return Invalid(absl::StrCat("--", name, "=", address,
                                ": expected host:port with a port 0-65535 (0: any free port; "
                                "[addr]:port for IPv6)"));
  }
  return absl::OkStatus();
}

}  // namespace

void ConfigureUsage() {
  absl::FlagsUsageConfig config;
  auto ours = [](absl::string_view file) { return absl::EndsWith(file, "server_flags.cc"); };
  config.contains_helpshort_flags = ours;
  config.contains_help_flags = ours;
  absl::SetFlagsUsageConfig(config);
}

absl::StatusOr<ServerSettings> SettingsFromFlags() {
  ServerSettings s;
  s.listen = absl::GetFlag(FLAGS_listen);
  s.local_listen = absl::GetFlag(FLAGS_local_listen);
  s.metrics_listen = absl::GetFlag(FLAGS_metrics_listen);
  s.tls_cert = absl::GetFlag(FLAGS_tls_cert);
  s.tls_key = absl::GetFlag(FLAGS_tls_key);
  s.tls_client_ca = absl::GetFlag(FLAGS_tls_client_ca);
  s.drain_seconds = absl::GetFlag(FLAGS_drain_seconds);
  s.log_level = absl::GetFlag(FLAGS_log_level);
  s.exit_when_stdin_closes = absl::GetFlag(FLAGS_exit_when_stdin_closes);
  if (absl::Status valid = CheckListenAddress("listen", s.listen); !valid.ok()) return valid;
  if (!s.local_listen.empty()) {
    if (absl::Status valid = CheckListenAddress("local_listen", s.local_listen); !valid.ok()) {
      return valid;
    }
  }
  if (!s.metrics_listen.empty()) {
    if (absl::Status valid = CheckListenAddress("metrics_listen", s.metrics_listen); !valid.ok()) {
      return valid;
    }
  }
  if (!s.local_listen.empty() && !IsLoopback(s.local_listen)) {
    return Invalid(absl::StrCat("--local_listen=", s.local_listen,
                                ": must be a loopback address (127.x.x.x:PORT, [::1]:PORT or "
                                "localhost:PORT); it is plaintext"));
  }
  if (s.tls_cert.empty() != s.tls_key.empty()) {
    return Invalid("--tls_cert and --tls_key go together");
  }
  if (!s.tls_client_ca.empty() && s.tls_cert.empty()) {
    return Invalid("--tls_client_ca needs --tls_cert and --tls_key");
  }

  ServerOptions& server = s.server;
  server.keepalive_seconds = absl::GetFlag(FLAGS_keepalive_seconds);
  server.keepalive_timeout_seconds = absl::GetFlag(FLAGS_keepalive_timeout_seconds);
  server.max_connection_idle_seconds = absl::GetFlag(FLAGS_max_connection_idle_seconds);
  server.reflection = absl::GetFlag(FLAGS_reflection);
  server.max_streams_per_connection = absl::GetFlag(FLAGS_max_streams_per_connection);
  server.handshake_seconds = absl::GetFlag(FLAGS_handshake_timeout_seconds);
  server.max_side_streams = absl::GetFlag(FLAGS_max_health_and_reflection_streams);
  if (server.max_streams_per_connection < 1) {
    return Invalid(absl::StrCat("--max_streams_per_connection: must be >= 1, got ",
                                server.max_streams_per_connection));
  }
  if (server.max_side_streams < 1) {
    return Invalid(absl::StrCat("--max_health_and_reflection_streams: must be >= 1, got ",
                                server.max_side_streams));
  }
  for (auto [name, value] : {std::pair{"keepalive_seconds", server.keepalive_seconds},
                             {"keepalive_timeout_seconds", server.keepalive_timeout_seconds},
                             {"max_connection_idle_seconds", server.max_connection_idle_seconds},
                             {"handshake_timeout_seconds", server.handshake_seconds}}) {
    if (!Positive(value)) return Invalid(absl::StrCat("--", name, ": must be > 0, got ", value));
  }
  if (absl::Status valid = CheckSeconds("drain_seconds", s.drain_seconds, true); !valid.ok()) {
    return valid;
  }

  ServiceConfig& service = s.service;
  service.refine_threads = absl::GetFlag(FLAGS_threads);
  wire::ServiceLimits& l = service.limits;
  l.max_voxels = absl::GetFlag(FLAGS_max_voxels);
  l.max_input_tets = absl::GetFlag(FLAGS_max_input_tets);
  l.max_concurrent_refinements = absl::GetFlag(FLAGS_max_concurrent);
  l.max_message_bytes = absl::GetFlag(FLAGS_max_message_bytes);
  l.max_iterations = absl::GetFlag(FLAGS_max_iterations);
  l.max_lattice_n = absl::GetFlag(FLAGS_max_lattice_n);
  l.max_lattice_points = absl::GetFlag(FLAGS_max_lattice_points);
  l.max_call_seconds = absl::GetFlag(FLAGS_max_call_seconds);
  l.input_deadline_seconds = absl::GetFlag(FLAGS_input_deadline_seconds);
  l.idle_timeout_seconds = absl::GetFlag(FLAGS_idle_timeout_seconds);
  l.write_stall_seconds = absl::GetFlag(FLAGS_write_stall_seconds);
  l.queue_seconds = absl::GetFlag(FLAGS_queue_seconds);
  l.max_calls_per_identity = absl::GetFlag(FLAGS_max_calls_per_identity);
  service.max_slots_per_identity = absl::GetFlag(FLAGS_max_slots_per_identity);
  l.bytes_per_output_tet = absl::GetFlag(FLAGS_bytes_per_output_tet);
  // Each bound named on its own (one message listing nine flags left the operator to find
  // which was wrong).
  for (auto [name, value, least] : {std::tuple<const char*, int64_t, int64_t>{
                                        "max_concurrent", l.max_concurrent_refinements, 1},
                                    {"max_voxels", l.max_voxels, 1},
                                    {"max_input_tets", l.max_input_tets, 1},
                                    {"bytes_per_output_tet", l.bytes_per_output_tet, 1},
                                    {"max_message_bytes", l.max_message_bytes, 1024},
                                    {"max_iterations", l.max_iterations, 0},
                                    {"max_lattice_points", l.max_lattice_points, 0},
                                    {"max_calls_per_identity", l.max_calls_per_identity, 0},
                                    {"max_slots_per_identity", service.max_slots_per_identity, 0},
                                    {"threads", service.refine_threads, 0}}) {
    if (value < least) {
      return Invalid(absl::StrCat("--", name, ": must be >= ", least, ", got ", value));
    }
  }
  if (service.max_slots_per_identity == 0) {
    service.max_slots_per_identity = std::max(1, l.max_concurrent_refinements - 1);
  }
  if (l.max_lattice_n < 0 || l.max_lattice_n > 64) {
    return Invalid(absl::StrCat("--max_lattice_n: must be in [0, 64] (the core's bound), got ",
                                l.max_lattice_n));
  }
  for (auto [name, value] : {std::pair{"max_call_seconds", l.max_call_seconds},
                             {"input_deadline_seconds", l.input_deadline_seconds},
                             {"idle_timeout_seconds", l.idle_timeout_seconds},
                             {"write_stall_seconds", l.write_stall_seconds}}) {
    if (absl::Status valid = CheckSeconds(name, value, false); !valid.ok()) return valid;
  }
  if (absl::Status valid = CheckSeconds("queue_seconds", l.queue_seconds, true); !valid.ok()) {
    return valid;
  }

  // Memory: the limit, the budget the calls share, and the tet budget that fits it.
  s.memory_limit_bytes = absl::GetFlag(FLAGS_memory_limit_bytes);
  if (s.memory_limit_bytes < 0) return Invalid("--memory_limit_bytes: must be >= 0");
  if (s.memory_limit_bytes > 0) {
    s.memory_source = "--memory_limit_bytes";
  } else if (std::optional<int64_t> cgroup = CgroupMemoryLimit()) {
    s.memory_limit_bytes = *cgroup;
    s.memory_source = "the cgroup limit";
  } else {
    s.memory_limit_bytes = PhysicalMemoryBytes();
    s.memory_source = "physical memory (no cgroup limit)";
  }
  if (absl::GetFlag(FLAGS_memory_limit_bytes) == 0) {
    // Under `ulimit -v` (or -d) an allocation fails before the cgroup or the machine runs out.
    if (std::optional<int64_t> left = AddressSpaceLeft(); left && *left < s.memory_limit_bytes) {
      s.memory_limit_bytes = *left;
      s.memory_source = "the address space left under ulimit -v / -d (RLIMIT_AS, RLIMIT_DATA)";
    }
  }
  l.memory_budget_bytes = absl::GetFlag(FLAGS_memory_budget_bytes);
  if (l.memory_budget_bytes < 0) return Invalid("--memory_budget_bytes: must be >= 0");
  if (l.memory_budget_bytes == 0) l.memory_budget_bytes = BudgetForLimit(s.memory_limit_bytes);
  if (l.memory_budget_bytes > s.memory_limit_bytes) {
    return Invalid(absl::StrCat("--memory_budget_bytes=", l.memory_budget_bytes,
                                " exceeds the memory limit of ", s.memory_limit_bytes, " (",
                                s.memory_source, ")"));
  }
  s.server.grpc_memory_bytes = absl::GetFlag(FLAGS_grpc_memory_bytes);
  if (s.server.grpc_memory_bytes < 0) return Invalid("--grpc_memory_bytes: must be >= 0");
  if (s.server.grpc_memory_bytes == 0) {
    s.server.grpc_memory_bytes =
        std::max<int64_t>(int64_t{64} << 20, s.memory_limit_bytes - l.memory_budget_bytes);
  }
  // Half the budget for one client's uploads (server/call_gate.h), so that one client's slow
  // uploads cannot keep every other client's calls out.
  service.max_input_bytes_per_identity = l.memory_budget_bytes / 2;
  const int64_t call_floor = OpenCallBytes(l.max_message_bytes);
  if (l.memory_budget_bytes < call_floor) {
    return Invalid(absl::StrCat("the memory budget (", HumanBytes(l.memory_budget_bytes),
                                ") cannot hold even one open call (2 x --max_message_bytes)"));
  }
  l.max_output_tets = absl::GetFlag(FLAGS_max_output_tets);
  if (l.max_output_tets < 0) return Invalid("--max_output_tets: must be >= 0");
  // A call that may reach the tet budget reserves it whole; when even one such call cannot fit
  // the memory budget, every call with default options is refused (and a budget computed as 1
  // tet returned every mesh unrefined): a server that cannot do its job must not start.
  const int64_t fitting_tets = (l.memory_budget_bytes - call_floor) / l.bytes_per_output_tet;
  if (l.max_output_tets == 0) {
    // --max_concurrent calls at the default budget must fit the memory budget together with
    // their inputs: a tenth of the budget is left for the inputs (a 1.8 GiB budget takes 180 MiB
    // of volumes and meshes). Until 2026-11-28 one call took the 90% (50 M tets, 7.5 GiB, on a
    // 24 GiB machine), so two calls with default options held the budget and a third, of one
    // tet, waited its queue time and was refused, on a server that said --max_concurrent 4
    // (found by a service sweep). A single larger call asks for it: --max_output_tets.
    const int64_t concurrent = std::max(1, l.max_concurrent_refinements);
    l.max_output_tets = std::min<int64_t>(
        (l.memory_budget_bytes / 10 * 9 / concurrent - call_floor) / l.bytes_per_output_tet,
        50'000'000);
    if (l.max_output_tets < kMinOutputTets) {
      return Invalid(absl::StrCat(
          "the memory budget (", HumanBytes(l.memory_budget_bytes), ", from ", s.memory_source,
          ") leaves room for ", std::max<int64_t>(0, l.max_output_tets),
          " output tets a call at --bytes_per_output_tet=", l.bytes_per_output_tet, " with ",
          concurrent, " calls at once (--max_concurrent), fewer than ", kMinOutputTets,
          ": raise --memory_limit_bytes or --memory_budget_bytes, or lower --max_concurrent"));
    }
  } else if (l.max_output_tets > fitting_tets) {
    return Invalid(absl::StrCat("--max_output_tets=", l.max_output_tets,
                                ": a call that reaches it needs ",
                                HumanBytes(call_floor + l.max_output_tets * l.bytes_per_output_tet),
                                " (", l.bytes_per_output_tet,
                                " bytes a tet, --bytes_per_output_tet), more than the memory "
                                "budget of ",
                                HumanBytes(l.memory_budget_bytes), " (from ", s.memory_source,
                                "): at most ", std::max<int64_t>(0, fitting_tets), " fit"));
  }
  // What one client's calls may hold together (server/call_gate.h): the budget less one call
  // with default options (at the tet budget, with its share of the tenth of the budget kept for
  // inputs), so that another client's such call always fits beside them; at least half the
  // budget. With the defaults that is three quarters: one client still runs --max_concurrent
  // less one default calls at once (the slot rule's cap).
  {
    const int64_t concurrent = std::max(1, l.max_concurrent_refinements);
    const int64_t one_call = call_floor + l.max_output_tets * l.bytes_per_output_tet +
                             l.memory_budget_bytes / 10 / concurrent;
    service.max_bytes_per_identity =
        std::max(l.memory_budget_bytes / 2, l.memory_budget_bytes - one_call);
  }

  // Identity.
  if (const std::string path = absl::GetFlag(FLAGS_token_file); !path.empty()) {
    absl::StatusOr<TokenTable> tokens = TokenTable::FromFile(path);
    if (!tokens.ok())
      return absl::Status(tokens.status().code(),
                          absl::StrCat("--token_file: ", tokens.status().message()));
    service.access.tokens = *std::move(tokens);
  }
  for (absl::string_view subject :
       absl::StrSplit(absl::GetFlag(FLAGS_tls_allowed_subjects), ';', absl::SkipWhitespace())) {
    service.access.allowed_subjects.emplace_back(absl::StripAsciiWhitespace(subject));
  }
  service.access.require_client_certificate = !s.tls_client_ca.empty();
  if (!service.access.allowed_subjects.empty() && s.tls_client_ca.empty()) {
    return Invalid("--tls_allowed_subjects needs --tls_client_ca (clients must send certificates)");
  }
  return s;
}

}  // namespace tetrefine::server
