#pragma once

#include <string>

namespace tetrefine::io {

// The temporary files this process has on disk while it writes (file_bytes.h: a file written
// beside its destination and renamed over it, and staged files awaiting Commit), so that a
// signal that ends the process mid-write does not leave them behind. An outside review
// (2026-11-29) found `tetrefine mesh`, `slice` and `plot` killed by SIGTERM during a write each
// left a hidden ".name.tmp.PID.N" file; only `refine` caught the signal.

// Installs handlers for SIGINT, SIGTERM and SIGHUP that remove every registered temporary and
// then end the process by the same signal with its default action, so that the exit status and
// what the parent sees are as before. A signal the process was started with ignored (SIGHUP
// under nohup, SIGINT in a background job) stays ignored. For a program's main, once, before
// any thread starts; a command that handles these signals itself (refine's InterruptGuard)
// replaces the handlers while it runs and restores them after.
void RemoveTemporariesOnSignals();

// The same handler for `signal_number` alone, whatever its action now. Async-signal-safe: a
// command's own handler calls it from its handler so that the next signal ends the process at
// once, with its temporaries removed (cli/interrupt_guard.h).
void RemoveTemporariesOnSignal(int signal_number);

// A temporary file registered for removal by those handlers while the object lives. Paths
// longer than the registry's slot (4095 bytes) or beyond its 256 slots are not registered (the
// write goes on; only the clean-up on a signal is lost). Movable, not copyable.
class RegisteredTemporary {
 public:
  RegisteredTemporary() = default;
  explicit RegisteredTemporary(const std::string& path);
  RegisteredTemporary(RegisteredTemporary&& other) noexcept;
  RegisteredTemporary& operator=(RegisteredTemporary&& other) noexcept;
  RegisteredTemporary(const RegisteredTemporary&) = delete;
  RegisteredTemporary& operator=(const RegisteredTemporary&) = delete;
  // Unregisters, without touching the file: call after the file was renamed or removed, so that
  // a signal in between finds the path gone (unlinking it then is harmless: the name, with this
  // process's id in it, is no other file's).
  ~RegisteredTemporary();

  bool registered() const { return slot_ >= 0; }

 private:
  int slot_ = -1;
};

// While one lives, the renames of a set of files into place (StagedFiles::Commit: a TetGen
// .node and .ele, a .pvtu and its pieces) are not cut short by those handlers: a signal that
// comes meanwhile ends the process when the last window closes. Without it, a signal between
// the .node's rename and the .ele's left a new .node beside an old .ele (an outside review's
// reproduction, rerun on the staged writer, 2026-11-29).
class CommitWindow {
 public:
  CommitWindow();
  ~CommitWindow();
  CommitWindow(const CommitWindow&) = delete;
  CommitWindow& operator=(const CommitWindow&) = delete;
};

// Temporaries registered now (tests).
int RegisteredTemporaryCountForTesting();

}  // namespace tetrefine::io
