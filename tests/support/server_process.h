#pragma once

// A real tetrefine_server child process on loopback, for the tests that need the binary itself:
// its flags, its logs, its metrics endpoint, a replica that can be killed, a drain on SIGTERM.

#include <chrono>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "grpcpp/grpcpp.h"
#include "tests/support/child_process.h"

namespace tetrefine::testing {

class ServerProcess {
 public:
  // Starts the tetrefine_server under test with --listen=127.0.0.1:<port> (0: a free port,
  // which the server logs), --metrics_listen=127.0.0.1:0 (tests never listen beyond this host)
  // and then `flags` (a later flag overrides: "--metrics_listen=" turns metrics off). Waits up
  // to 30 s for the listening line; UNAVAILABLE with the server's output if none comes.
  // `address_space_bytes` > 0 runs it under that RLIMIT_AS, as a memory-limited container would.
  static absl::StatusOr<std::unique_ptr<ServerProcess>> Start(
      const std::vector<std::string>& flags = {}, int port = 0, int64_t address_space_bytes = 0);

  // SIGTERM (a graceful exit, so that coverage and leak reports are written), then SIGKILL if
  // it still runs after 10 s.
  ~ServerProcess();
  ServerProcess(const ServerProcess&) = delete;
  ServerProcess& operator=(const ServerProcess&) = delete;

  int port() const { return port_; }
  std::string target() const { return "127.0.0.1:" + std::to_string(port_); }
  // The port of "metrics on http://127.0.0.1:PORT/metrics", or 0 if none was logged.
  int metrics_port() const { return metrics_port_; }
  // Everything the server has logged so far.
  std::string Log() const { return process_->Output(); }
  ChildProcess& process() { return *process_; }

  // A channel with its own connection (distinct arguments), connected within 10 s.
  std::shared_ptr<grpc::Channel> NewChannel() const;

  // SIGTERM, then the exit code, or nullopt when still running after `timeout`.
  std::optional<int> Stop(std::chrono::milliseconds timeout = std::chrono::seconds(30));
  // SIGKILL now (a replica that dies mid-call) and reap it.
  void Kill();

 private:
  ServerProcess() = default;

  std::unique_ptr<ChildProcess> process_;
  int port_ = 0;
  int metrics_port_ = 0;
};

// A channel to `target` with its own connection (separate clients do not share one), not yet
// connected.
std::shared_ptr<grpc::Channel> NewUnsharedChannel(const std::string& target);

// The body of GET http://127.0.0.1:port/path (10 s timeout); an error for anything but 200.
absl::StatusOr<std::string> HttpGet(int port, const std::string& path);

}  // namespace tetrefine::testing
