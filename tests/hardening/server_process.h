#pragma once

#include <chrono>
#include <memory>
#include <string>
#include <vector>

#include "grpcpp/grpcpp.h"
#include "tests/hardening/child_process.h"

namespace tetrefine::hardening {

// A real tetrefine_server process on loopback. Port 0 lets the server pick a free port, which it
// logs; Start waits for that line.
class ServerProcess {
 public:
  // Null (with the server's output in *error) when it does not come up within 30 s.
  // `address_space_bytes` > 0 runs it under that RLIMIT_AS, as a memory-limited container would.
  static std::unique_ptr<ServerProcess> Start(const std::vector<std::string>& flags, int port = 0,
                                              std::string* error = nullptr,
                                              int64_t address_space_bytes = 0);

  int port() const { return port_; }
  std::string target() const { return "127.0.0.1:" + std::to_string(port_); }
  ChildProcess& process() { return *process_; }

  // A channel with its own connection (distinct arguments), connected within 10 s.
  std::shared_ptr<grpc::Channel> NewChannel() const;

  // SIGTERM, then the exit code, or nullopt when still running after `timeout`.
  std::optional<int> Stop(std::chrono::milliseconds timeout = std::chrono::seconds(30));

 private:
  std::unique_ptr<ChildProcess> process_;
  int port_ = 0;
};

// A channel to `target` with its own connection, not yet connected.
std::shared_ptr<grpc::Channel> NewUnsharedChannel(const std::string& target);

}  // namespace tetrefine::hardening
