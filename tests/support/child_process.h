#pragma once

// The one way tests start another program: ChildProcess (a process that runs beside the test,
// its output captured as it comes) and RunProcess (a program run to completion).

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

namespace tetrefine::testing {

struct ChildOptions {
  std::string cwd;               // empty: the test's working directory
  bool separate_stderr = false;  // false: stderr goes to the same capture as stdout
};

// A child process whose stdout and stderr are captured (a thread drains each pipe, so the child
// never blocks on a full one). Its stdin is /dev/null; it gets SIGKILL if the test process dies
// first. The destructor kills (SIGKILL) and reaps it if it is still running. Every wait is
// bounded.
class ChildProcess {
 public:
  // Starts argv[0] (a path) with the arguments that follow; null when it cannot be started.
  static std::unique_ptr<ChildProcess> Start(const std::vector<std::string>& argv,
                                             const ChildOptions& options = {});
  ~ChildProcess();
  ChildProcess(const ChildProcess&) = delete;
  ChildProcess& operator=(const ChildProcess&) = delete;

  pid_t pid() const { return pid_; }

  // Waits until a line of the (stdout) capture containing `needle` has been printed; that line,
  // or nullopt on timeout or when the child closed its output first.
  std::optional<std::string> WaitForLine(std::string_view needle,
                                         std::chrono::milliseconds timeout);
  // The stdout capture so far (with stderr unless separate_stderr), whole and line by line.
  std::string Output() const;
  std::vector<std::string> Lines() const;
  // The stderr capture so far (empty unless separate_stderr).
  std::string ErrorOutput() const;

  void Signal(int signal_number) const;
  // Waits for the child to exit: its exit code (128 + signal when killed), or nullopt if it
  // still runs after `timeout`.
  std::optional<int> WaitExit(std::chrono::milliseconds timeout);
  // Waits until both captures have reached end of file (the child and anything that inherited
  // its output are gone); false on timeout.
  bool WaitOutputClosed(std::chrono::milliseconds timeout);

  // A numeric field of /proc/<pid>/status (e.g. "VmRSS" in kB, "Threads"); -1 once the process
  // is gone.
  int64_t StatusField(std::string_view name) const;
  int64_t RssKb() const { return StatusField("VmRSS"); }
  // User plus system CPU time so far, seconds (resolution: one clock tick).
  double CpuSeconds() const;

 private:
  ChildProcess() = default;
  void Drain(int fd, int stream);

  pid_t pid_ = -1;
  std::optional<int> exit_code_;
  mutable std::mutex mu_;
  std::condition_variable changed_;
  std::string text_[2];  // stdout (and merged stderr), stderr
  int open_streams_ = 0;
  std::vector<std::thread> drains_;
};

// Splits `text` into lines (a final newline does not start an empty line).
std::vector<std::string> SplitLines(const std::string& text);

// A program run to completion.
struct ProcessResult {
  int exit_code = -1;  // 128 + signal when killed by a signal
  std::string out;
  std::string err;
  bool timed_out = false;
  double seconds = 0.0;
};

// Runs `argv` (argv[0] is the program path) in `cwd` (empty: ours) with stdin on /dev/null,
// collecting stdout and stderr apart. Killed with SIGKILL after `timeout_seconds`.
ProcessResult RunProcess(const std::vector<std::string>& argv, const std::string& cwd = "",
                         double timeout_seconds = 120.0);

// Polls `process` until its CPU time stops growing (less than `slack` seconds over `window`).
// Returns how long after the call the idle window began (how long the process kept working), or
// `timeout` if it never went idle.
std::chrono::milliseconds TimeUntilCpuIdle(const ChildProcess& process,
                                           std::chrono::milliseconds window,
                                           std::chrono::milliseconds timeout, double slack = 0.03);

}  // namespace tetrefine::testing
