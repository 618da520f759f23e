#pragma once

#include <string>

namespace tetrefine::cli {

// Ctrl-C, and SIGTERM or SIGHUP (what `timeout`, batch schedulers, container runtimes and a
// closed terminal send), while a command that can stop cleanly runs (refine: the call is
// cancelled, the embedded service stops within an iteration's polling interval, a file being
// written is finished). While a guard lives, the first of these signals is recorded
// (Interrupted) and the command decides when to stop; from then on any of the three ends the
// process at once, removing its temporary files (client/io/temporary_files.h), so that a user
// can still stop a run stuck in a slow write. A signal the process was started with ignored
// (SIGHUP under nohup, SIGINT in a background job) stays ignored. The destructor restores the
// handlers that were there before (main's, which remove temporaries and end the process).
//
// Found by outside reviews: SIGTERM and SIGHUP killed refine at once, leaving a hidden temporary
// file of the output being written (2026-11-29); the guard caught SIGHUP under nohup, so a closed
// terminal ended the run; a second, different signal did not end it (each signal's own handler
// was reset, only for that signal) and a second signal during a long write(2) waited for it.
class InterruptGuard {
 public:
  InterruptGuard();
  ~InterruptGuard();
  InterruptGuard(const InterruptGuard&) = delete;
  InterruptGuard& operator=(const InterruptGuard&) = delete;

  // The first signal caught since the guard was made, or 0.
  static int Interrupted();
  // What a run says it was stopped by: "interrupted", "terminated (SIGTERM)", "hung up
  // (SIGHUP)"; empty when Interrupted() is 0.
  static std::string InterruptedBy();
};

}  // namespace tetrefine::cli
