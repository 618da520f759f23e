#include "server/shutdown_signals.h"

#include <pthread.h>
#include <signal.h>

#include <ctime>

#include "spdlog/spdlog.h"

namespace tetrefine::server {
namespace {

// Whether the process was started with `signal_number` ignored (SIGHUP under nohup, SIGINT in
// a background job). Blocking such a signal would undo that: the kernel queues a blocked signal
// whatever its disposition, so sigwait would take it. `nohup tetrefine_server &` drained and
// exited when its terminal closed until a read-through (2026-11-29) noticed.
bool IgnoredAtStart(int signal_number) {
  struct sigaction current = {};
  return sigaction(signal_number, nullptr, &current) == 0 && current.sa_handler == SIG_IGN;
}

// The signals that start the drain: SIGINT, SIGTERM and SIGHUP, less those ignored at start
// (read once, before any thread: nothing changes the dispositions after).
sigset_t ShutdownSet() {
  static const sigset_t set = [] {
    sigset_t s;
    sigemptyset(&s);
    // A closed terminal (or `kill -HUP`) used to kill the server at once, cutting off its
    // calls: it drains like SIGTERM. Nothing is reloaded on it.
    for (const int signal_number : {SIGINT, SIGTERM, SIGHUP}) {
      if (!IgnoredAtStart(signal_number)) sigaddset(&s, signal_number);
    }
    return s;
  }();
  return set;
}

}  // namespace

void ShutdownSignals::BlockInThisThread() {
  const sigset_t set = ShutdownSet();
  pthread_sigmask(SIG_BLOCK, &set, nullptr);
}

ShutdownSignals::ShutdownSignals() {
  std::thread([this] { Loop(); }).detach();
}

int ShutdownSignals::Wait() {
  std::unique_lock<std::mutex> lock(mu_);
  first_cv_.wait(lock, [&] { return first_.has_value(); });
  return *first_;
}

void ShutdownSignals::SetDrainDeadline(std::chrono::system_clock::time_point deadline) {
  std::lock_guard<std::mutex> lock(mu_);
  drain_deadline_ = deadline;
}

void ShutdownSignals::Loop() {
  const sigset_t set = ShutdownSet();
  for (;;) {
    int signal_number = 0;
    if (sigwait(&set, &signal_number) != 0) continue;
    std::lock_guard<std::mutex> lock(mu_);
    if (!first_.has_value()) {
      first_ = signal_number;
      first_cv_.notify_all();
      continue;
    }
    if (drain_deadline_.has_value()) {
      const double left =
          std::chrono::duration<double>(*drain_deadline_ - std::chrono::system_clock::now())
              .count();
      spdlog::warn(
          "signal {} again while draining: ignored; in-flight calls have {:.1f} s left before "
          "they are cancelled (--drain_seconds)",
          signal_number, std::max(0.0, left));
    } else {
      spdlog::warn("signal {} again while starting the drain: ignored", signal_number);
    }
  }
}

}  // namespace tetrefine::server
