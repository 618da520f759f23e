#pragma once

// A bound on how many log lines a stream of similar events writes.

#include <chrono>
#include <cstdint>
#include <mutex>
#include <string>

namespace tetrefine::server {

// At most `per_second` lines in any one-second window; the lines past that are counted, and the
// count is handed to the next line that may be written. Why: every refused call wrote an access
// line, and a flood of refused calls (141 k in 15 s) wrote 47 MB of log, which fills a
// container's disk and drowns the lines that matter (an outside review, 2026-11-29). Calls that
// were admitted to refine are not limited. Thread-safe.
class LogRateLimit {
 public:
  using Clock = std::chrono::steady_clock;

  // per_second >= 1.
  explicit LogRateLimit(int per_second) : per_second_(per_second) {}
  LogRateLimit(const LogRateLimit&) = delete;
  LogRateLimit& operator=(const LogRateLimit&) = delete;

  // True when a line may be written at `now`; then *suppressed is the number of lines refused
  // since the last one allowed (0 if none), for the line to say.
  bool Allow(int64_t* suppressed, Clock::time_point now = Clock::now());

  // What a line says of the `suppressed` lines Allow counted: "" for none, else
  // " (N calls refused since the last such line were not logged)".
  static std::string SuppressedNote(int64_t suppressed);

 private:
  std::mutex mu_;
  const int per_second_;
  Clock::time_point window_start_{};
  int in_window_ = 0;
  int64_t dropped_ = 0;
};

}  // namespace tetrefine::server
