#pragma once

// The tetrefine_server command line: every flag (server_flags.cc, which `--help` lists) and the
// configuration it makes.

#include <string>

#include "absl/status/statusor.h"
#include "server/metrics.h"
#include "server/refiner_service.h"
#include "server/server_setup.h"

namespace tetrefine::server {

struct ServerSettings {
  std::string listen;          // host:port of the gRPC listener
  std::string local_listen;    // loopback host:port of a plaintext listener for probes; "": none
  std::string metrics_listen;  // host:port of /metrics; "": none
  ServiceConfig service;       // limits (caps, time limits, memory budget), access, threads
  ServerOptions server;        // keepalive, reflection
  std::string tls_cert, tls_key, tls_client_ca;  // PEM files; empty: plaintext gRPC
  double drain_seconds = 30;
  std::string log_level;
  // Drain and exit, as on SIGTERM, when standard input reaches its end: the parent that started
  // this server holds the pipe's other end, and the kernel closes it when the parent dies however
  // it dies (python/tetrefine/local_server.py).
  bool exit_when_stdin_closes = false;
  std::string memory_source;  // where the memory limit came from, for the startup log
  int64_t memory_limit_bytes = 0;
};

// Makes `--help` list the flags of server_flags.cc (absl lists only those of a file named like
// the program by default, which printed "No flags matched").
void ConfigureUsage();

// The settings the parsed flags give, checked: INVALID_ARGUMENT naming the flag, or the token
// file's own error.
absl::StatusOr<ServerSettings> SettingsFromFlags();

}  // namespace tetrefine::server
