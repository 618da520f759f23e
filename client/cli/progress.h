#pragma once

// The progress lines of long-running commands on stderr: one line per phase, begun when the
// phase starts ("tetrefine: reading volume head.nii.gz ... ") and finished with what it did and
// how long it took ("256x256x150 int16, 9.4 MB, 0.21 s"), so a run never goes silent for long
// without saying what it is doing. Silenced as a whole by --quiet.

#include <chrono>
#include <cstdint>
#include <string>

namespace tetrefine::cli {

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

  bool quiet() const { return quiet_; }

 private:
  bool quiet_;
  bool open_ = false;
  std::chrono::steady_clock::time_point start_;
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
