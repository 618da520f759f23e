#pragma once

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <map>
#include <mutex>
#include <thread>
#include <unordered_map>
#include <utility>

namespace tetrefine::server {

// Runs callbacks at given times on one thread of its own: the time limits of every call (input
// deadline, idle timeout, queue wait, write stall, the call's wall time) are entries here rather
// than a thread or a gRPC alarm per call. Callbacks run one at a time and must be short (they
// finish or cancel a call, never wait on one).
class Watchdog {
 public:
  using Clock = std::chrono::steady_clock;
  using Id = uint64_t;  // never 0

  Watchdog();
  // Stops the thread; callbacks not yet run are dropped.
  ~Watchdog();
  Watchdog(const Watchdog&) = delete;
  Watchdog& operator=(const Watchdog&) = delete;

  // Runs `callback` on the watchdog thread at `when` (at once if it has passed).
  Id Schedule(Clock::time_point when, std::function<void()> callback);

  // Removes a callback that has not run. If it is running right now on another thread, waits
  // until it has returned, so that after Cancel nothing it refers to is used any more. Called from
  // the callback itself, it returns at once. Unknown or already-run ids are ignored.
  void Cancel(Id id);

 private:
  void Loop();

  std::mutex mu_;
  std::condition_variable changed_;
  // Pending callbacks by (time, id): ids break ties in scheduling order.
  std::map<std::pair<Clock::time_point, Id>, std::function<void()>> pending_;
  std::unordered_map<Id, Clock::time_point> when_;
  Id next_id_ = 1;
  Id running_ = 0;  // the callback being run, 0 for none
  bool stopping_ = false;
  std::thread thread_;  // last: started once the rest exists
};

}  // namespace tetrefine::server
