#pragma once

#include <sys/types.h>

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <string_view>
#include <thread>
#include <vector>

namespace tetrefine::hardening {

// A child process whose stdout and stderr are captured line by line (a thread drains the pipe,
// so the child never blocks on a full one). The destructor kills (SIGKILL) and reaps it if it is
// still running. Every wait is bounded.
class ChildProcess {
 public:
  // Starts argv[0] with the arguments that follow; null when it cannot be started.
  static std::unique_ptr<ChildProcess> Start(const std::vector<std::string>& argv);
  ~ChildProcess();
  ChildProcess(const ChildProcess&) = delete;
  ChildProcess& operator=(const ChildProcess&) = delete;

  pid_t pid() const { return pid_; }

  // Waits until a line containing `needle` has been printed; that line, or nullopt on timeout or
  // when the child closed its output first.
  std::optional<std::string> WaitForLine(std::string_view needle,
                                         std::chrono::milliseconds timeout);
  // Everything printed so far, one line per entry.
  std::vector<std::string> Lines() const;
  std::string Output() const;

  void Signal(int signal_number) const;
  // Waits for the child to exit: its exit code (128 + signal when killed), or nullopt if it
  // still runs after `timeout`.
  std::optional<int> WaitExit(std::chrono::milliseconds timeout);

  // A numeric field of /proc/<pid>/status (e.g. "VmRSS" in kB, "Threads"); -1 once the process
  // is gone.
  int64_t StatusField(std::string_view name) const;
  int64_t RssKb() const { return StatusField("VmRSS"); }
  // User plus system CPU time so far, seconds (resolution: one clock tick).
  double CpuSeconds() const;

 private:
  ChildProcess() = default;
  void Drain(int fd);

  pid_t pid_ = -1;
  std::optional<int> exit_code_;
  mutable std::mutex mu_;
  std::condition_variable changed_;
  std::vector<std::string> lines_;
  std::string partial_;
  bool closed_ = false;
  std::thread drain_;
};

// Polls `process` until its CPU time stops growing (less than `slack` seconds over `window`).
// Returns how long after the call the idle window began (how long the process kept working), or
// `timeout` if it never went idle.
std::chrono::milliseconds TimeUntilCpuIdle(const ChildProcess& process,
                                           std::chrono::milliseconds window,
                                           std::chrono::milliseconds timeout, double slack = 0.03);

}  // namespace tetrefine::hardening
