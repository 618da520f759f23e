#pragma once

// The progress lines of long-running commands on stderr: one line per phase, begun when the
// phase starts ("tetrefine: reading volume head.nii.gz ... ") and finished with what it did and
// how long it took ("256x256x150 int16, 9.4 MB, 0.21 s"), so a run never goes silent for long
// without saying what it is doing. Silenced as a whole by --quiet.

#include <chrono>
#include <cstdint>
#include <functional>
#include <mutex>
#include <string>
#include <thread>

namespace tetrefine::cli {

// Thread-safe: a helper thread may print lines (LineIfIdle) while the main thread runs phases.
class Progress {
 public:
  // `quiet`: print nothing at all.
  explicit Progress(bool quiet) : quiet_(quiet) {}

  // Starts a phase: prints "tetrefine: <what> ... " without ending the line, and starts its
  // clock. A phase still open is abandoned first.
  void Begin(const std::string& what);
  // Ends the open phase's line with "<detail>, <seconds> s". No phase open: nothing.
  void End(const std::string& detail);
  // Ends the open phase's line with "failed", so that the error message which follows starts a
  // line of its own. No phase open: nothing.
  void Abandon();
  // A complete line "tetrefine: <text>" (abandoning an open phase first).
  void Line(const std::string& text);
  // Line(text), unless a phase's line is open (it would be cut in two): then nothing. Returns
  // whether the line was printed (false also when quiet).
  bool LineIfIdle(const std::string& text);

  bool quiet() const { return quiet_; }

 private:
  void AbandonLocked();

  std::mutex mu_;
  bool quiet_;
  bool open_ = false;
  std::chrono::steady_clock::time_point start_;
};

// Says that a phase is still running when it has been silent for long: while armed and nothing
// was reported (Touch) for 2 s, prints describe(seconds of silence) through
// Progress::LineIfIdle, and again after 4, 8, 16, ... s of the same silence. For the phases the
// service does not announce (the final checks after the last iteration). Its lines depend on
// timing, so tests must not count on them.
class SilenceWatch {
 public:
  SilenceWatch(Progress& progress, std::function<std::string(double)> describe);
  ~SilenceWatch();  // stops the helper thread
  SilenceWatch(const SilenceWatch&) = delete;
  SilenceWatch& operator=(const SilenceWatch&) = delete;

  // Something was reported: the silence starts over. `armed`: whether to watch from now on.
  void Touch(bool armed);

 private:
  void Watch(const std::stop_token& stop);

  Progress& progress_;
  std::function<std::string(double)> describe_;
  std::mutex mu_;
  bool armed_ = false;
  std::chrono::steady_clock::time_point last_;
  double next_report_seconds_ = 2.0;
  std::jthread thread_;  // last: started once the members above exist, joined first
};

// Counts for people: "950", "12.3 k", "1.6 M", "2.1 G" (three significant digits at most).
std::string FormatCount(int64_t n);
// Sizes: "512 B", "12 kB", "31 MB", "1.2 GB" (powers of 1000, as file managers show them).
std::string FormatBytes(int64_t bytes);
// "0.42 s", "12.3 s".
std::string FormatSeconds(double seconds);
// Seconds since `start`, on the steady clock.
double SecondsSince(std::chrono::steady_clock::time_point start);

}  // namespace tetrefine::cli
