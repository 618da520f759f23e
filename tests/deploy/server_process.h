#pragma once

// A real tetrefine_server child process on loopback ports, for tests that need the binary itself
// (its flags, its metrics endpoint, a replica that can be killed).

#include <sys/types.h>

#include <condition_variable>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "absl/status/statusor.h"

namespace tetrefine::testing {

class ServerProcess {
 public:
  // Starts `binary` with --listen=127.0.0.1:0 and `flags`, and waits up to 30 s for the port it
  // logs. The child gets SIGKILL if this process dies first.
  static absl::StatusOr<std::unique_ptr<ServerProcess>> Start(
      const std::string& binary, const std::vector<std::string>& flags);

  // SIGTERM, then SIGKILL if it has not exited within 10 s.
  ~ServerProcess();
  ServerProcess(const ServerProcess&) = delete;
  ServerProcess& operator=(const ServerProcess&) = delete;

  // SIGKILL now (a replica that dies mid-call) and reap it.
  void Kill();

  int port() const { return port_; }
  std::string target() const;
  // The port of "metrics on http://127.0.0.1:PORT/metrics", or 0 if none was logged.
  int metrics_port() const { return metrics_port_; }
  // Everything the server has logged so far.
  std::string Log() const;

 private:
  ServerProcess() = default;
  void Pump(int fd);
  // The port in the first "<prefix>127.0.0.1:<port>" of `log`, or 0.
  static int PortIn(const std::string& log, const std::string& prefix);
  // Waits up to 30 s for such a line in the log (0 if none comes).
  int WaitForPort(const std::string& prefix);
  // The port if such a line is already there, else 0.
  int WaitForPortNow(const std::string& prefix);
  bool Reap(int timeout_ms);

  pid_t pid_ = -1;
  bool reaped_ = false;
  int port_ = 0;
  int metrics_port_ = 0;
  mutable std::mutex mu_;
  std::condition_variable changed_;
  std::string log_;
  bool eof_ = false;
  std::thread pump_;
};

// The body of GET http://127.0.0.1:port/path (10 s timeout); an error for anything but 200.
absl::StatusOr<std::string> HttpGet(int port, const std::string& path);

}  // namespace tetrefine::testing
