#pragma once

#include <chrono>
#include <condition_variable>
#include <mutex>
#include <optional>
#include <thread>

namespace tetrefine::server {

// SIGTERM, SIGINT and SIGHUP for a server that drains before it exits (each unless the process
// was started with it ignored, as nohup starts it with SIGHUP). They are blocked in every
// thread and taken by one thread of their own with sigwait: the first starts the drain (Wait
// returns it), and every later one is logged and ignored, so a second Ctrl-C or an impatient
// orchestrator cannot cut off the calls being drained; the drain's own deadline bounds it.
class ShutdownSignals {
 public:
  // Blocks SIGTERM, SIGINT and SIGHUP in the calling thread, whose mask every thread it starts
  // later inherits. Call first thing in main: gRPC starts its own threads on first use (even
  // creating credentials does), and a thread that does not block the signals would die of the
  // default action when the kernel picks it to take one.
  static void BlockInThisThread();

  // Starts the signal thread. BlockInThisThread must have run on this thread first.
  ShutdownSignals();
  // The thread stays blocked in sigwait until the process exits; it is detached.
  ~ShutdownSignals() = default;
  ShutdownSignals(const ShutdownSignals&) = delete;
  ShutdownSignals& operator=(const ShutdownSignals&) = delete;

  // Waits for the first signal and returns its number.
  int Wait();
  // Tells the signal thread how long the drain runs, for its log line about later signals.
  void SetDrainDeadline(std::chrono::system_clock::time_point deadline);

 private:
  void Loop();

  std::mutex mu_;
  std::condition_variable first_cv_;
  std::optional<int> first_;
  std::optional<std::chrono::system_clock::time_point> drain_deadline_;
};

}  // namespace tetrefine::server
