#include "tests/support/child_process.h"

#include <fcntl.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <fstream>
#include <sstream>
#include <utility>

namespace tetrefine::testing {

std::unique_ptr<ChildProcess> ChildProcess::Start(const std::vector<std::string>& argv,
                                                  const ChildOptions& options) {
  if (argv.empty()) return nullptr;
  // Everything the child needs is prepared before fork: between fork and exec only
  // async-signal-safe calls are allowed (the test process has gRPC threads).
  std::vector<char*> args;
  for (const std::string& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  const int streams = options.separate_stderr ? 2 : 1;
  int pipes[2][2] = {{-1, -1}, {-1, -1}};
  for (int s = 0; s < streams; ++s) {
    // Close-on-exec, so no other child (a server started earlier) holds a copy of these pipes.
    if (pipe2(pipes[s], O_CLOEXEC) != 0) {
      for (int t = 0; t < s; ++t) {
        close(pipes[t][0]);
        close(pipes[t][1]);
      }
      return nullptr;
    }
  }
  const char* cwd = options.cwd.empty() ? nullptr : options.cwd.c_str();
  const pid_t parent = getpid();
  const pid_t pid = fork();
  if (pid == 0) {
    prctl(PR_SET_PDEATHSIG, SIGKILL);
    if (getppid() != parent) _exit(127);
    const int devnull = open("/dev/null", O_RDONLY);
    dup2(devnull, STDIN_FILENO);
    dup2(pipes[0][1], STDOUT_FILENO);
    dup2(pipes[streams - 1][1], STDERR_FILENO);
    if (cwd != nullptr && chdir(cwd) != 0) _exit(127);
    execv(args[0], args.data());
    _exit(127);
  }
  for (int s = 0; s < streams; ++s) close(pipes[s][1]);
  if (pid < 0) {
    for (int s = 0; s < streams; ++s) close(pipes[s][0]);
    return nullptr;
  }
  std::unique_ptr<ChildProcess> child(new ChildProcess());
  child->pid_ = pid;
  child->open_streams_ = streams;
  for (int s = 0; s < streams; ++s) {
    child->drains_.emplace_back([raw = child.get(), fd = pipes[s][0], s] { raw->Drain(fd, s); });
  }
  return child;
}

void ChildProcess::Drain(int fd, int stream) {
  char buffer[4096];
  for (;;) {
    const ssize_t n = read(fd, buffer, sizeof(buffer));
    if (n < 0 && errno == EINTR) continue;
    std::lock_guard<std::mutex> lock(mu_);
    if (n <= 0) {
      --open_streams_;
      changed_.notify_all();
      break;
    }
    text_[stream].append(buffer, static_cast<size_t>(n));
    changed_.notify_all();
  }
  close(fd);
}

ChildProcess::~ChildProcess() {
  if (!exit_code_.has_value()) {
    kill(pid_, SIGKILL);
    WaitExit(std::chrono::seconds(10));
  }
  // The pipes close when the child (and any grandchild holding them) is gone.
  for (std::thread& drain : drains_) drain.join();
}

std::optional<std::string> ChildProcess::WaitForLine(std::string_view needle,
                                                     std::chrono::milliseconds timeout) {
  std::unique_lock<std::mutex> lock(mu_);
  size_t checked = 0;  // complete lines before this offset have been searched
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  for (;;) {
    const std::string& text = text_[0];
    for (size_t end; (end = text.find('\n', checked)) != std::string::npos; checked = end + 1) {
      const std::string_view line(text.data() + checked, end - checked);
      if (line.find(needle) != std::string_view::npos) return std::string(line);
    }
    if (open_streams_ == 0) {
      // A last line without a newline.
      const std::string_view rest(text.data() + checked, text.size() - checked);
      if (!rest.empty() && rest.find(needle) != std::string_view::npos) return std::string(rest);
      return std::nullopt;
    }
    if (changed_.wait_until(lock, deadline) == std::cv_status::timeout) return std::nullopt;
  }
}

std::string ChildProcess::Output() const {
  std::lock_guard<std::mutex> lock(mu_);
  return text_[0];
}

std::vector<std::string> ChildProcess::Lines() const { return SplitLines(Output()); }

std::string ChildProcess::ErrorOutput() const {
  std::lock_guard<std::mutex> lock(mu_);
  return text_[1];
}

void ChildProcess::Signal(int signal_number) const {
  if (!exit_code_.has_value()) kill(pid_, signal_number);
}

std::optional<int> ChildProcess::WaitExit(std::chrono::milliseconds timeout) {
  if (exit_code_.has_value()) return exit_code_;
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  for (;;) {
    int status = 0;
    const pid_t done = waitpid(pid_, &status, WNOHANG);
    if (done == pid_) {
      exit_code_ = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
      return exit_code_;
    }
    if (done < 0 || std::chrono::steady_clock::now() >= deadline) return std::nullopt;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
}

bool ChildProcess::WaitOutputClosed(std::chrono::milliseconds timeout) {
  std::unique_lock<std::mutex> lock(mu_);
  return changed_.wait_for(lock, timeout, [this] { return open_streams_ == 0; });
}

int64_t ChildProcess::StatusField(std::string_view name) const {
  std::ifstream status("/proc/" + std::to_string(pid_) + "/status");
  const std::string prefix = std::string(name) + ":";
  std::string line;
  while (std::getline(status, line)) {
    if (line.rfind(prefix, 0) == 0) return std::stoll(line.substr(prefix.size()));
  }
  return -1;
}

double ChildProcess::CpuSeconds() const {
  std::ifstream stat("/proc/" + std::to_string(pid_) + "/stat");
  std::string text;
  std::getline(stat, text);
  // The command name (field 2) is in parentheses and may hold spaces: count from after it.
  const size_t close = text.rfind(')');
  if (close == std::string::npos) return -1.0;
  std::istringstream fields(text.substr(close + 2));
  std::string field;
  // Fields 3..13 precede utime (14) and stime (15).
  for (int i = 3; i <= 13; ++i) fields >> field;
  uint64_t utime = 0, stime = 0;
  fields >> utime >> stime;
  return static_cast<double>(utime + stime) / static_cast<double>(sysconf(_SC_CLK_TCK));
}

std::vector<std::string> SplitLines(const std::string& text) {
  std::vector<std::string> lines;
  size_t begin = 0;
  while (begin < text.size()) {
    size_t end = text.find('\n', begin);
    if (end == std::string::npos) end = text.size();
    lines.push_back(text.substr(begin, end - begin));
    begin = end + 1;
  }
  return lines;
}

ProcessResult RunProcess(const std::vector<std::string>& argv, const std::string& cwd,
                         double timeout_seconds) {
  using Clock = std::chrono::steady_clock;
  ProcessResult result;
  const Clock::time_point start = Clock::now();
  std::unique_ptr<ChildProcess> child =
      ChildProcess::Start(argv, {.cwd = cwd, .separate_stderr = true});
  if (child == nullptr) {
    result.err = "cannot start " + (argv.empty() ? std::string("nothing") : argv[0]);
    return result;
  }
  const auto timeout = std::chrono::duration_cast<std::chrono::milliseconds>(
      std::chrono::duration<double>(timeout_seconds));
  std::optional<int> code = child->WaitExit(timeout);
  if (!code.has_value()) {
    result.timed_out = true;
    child->Signal(SIGKILL);
    code = child->WaitExit(std::chrono::seconds(10));
  }
  // The output is complete once the pipes close, shortly after the exit.
  child->WaitOutputClosed(std::chrono::seconds(10));
  result.exit_code = code.value_or(-1);
  result.out = child->Output();
  result.err = child->ErrorOutput();
  result.seconds = std::chrono::duration<double>(Clock::now() - start).count();
  return result;
}

std::chrono::milliseconds TimeUntilCpuIdle(const ChildProcess& process,
                                           std::chrono::milliseconds window,
                                           std::chrono::milliseconds timeout, double slack) {
  using Clock = std::chrono::steady_clock;
  const Clock::time_point start = Clock::now();
  std::vector<std::pair<Clock::time_point, double>> samples;
  for (;;) {
    const Clock::time_point now = Clock::now();
    samples.emplace_back(now, process.CpuSeconds());
    // The sample taken `window` ago (or the first) against now.
    size_t i = 0;
    while (i + 1 < samples.size() && now - samples[i + 1].first >= window) ++i;
    if (now - samples[i].first >= window && samples.back().second - samples[i].second < slack) {
      return std::chrono::duration_cast<std::chrono::milliseconds>(samples[i].first - start);
    }
    if (now - start >= timeout) return timeout;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
}

}  // namespace tetrefine::testing
