#include "tests/deploy/server_process.h"

#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/socket.h>
#include <sys/time.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstdlib>
#include <regex>

#include "absl/status/status.h"
#include "absl/strings/str_cat.h"

namespace tetrefine::testing {
namespace {

using Clock = std::chrono::steady_clock;

}  // namespace

absl::StatusOr<std::unique_ptr<ServerProcess>> ServerProcess::Start(
    const std::string& binary, const std::vector<std::string>& flags) {
  std::vector<std::string> args = {binary, "--listen=127.0.0.1:0"};
  args.insert(args.end(), flags.begin(), flags.end());
  std::vector<char*> argv;
  for (std::string& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);

  int pipe_fds[2];
  if (pipe2(pipe_fds, O_CLOEXEC) != 0) return absl::InternalError("pipe2 failed");
  const pid_t parent = getpid();
  const pid_t pid = fork();
  if (pid < 0) return absl::InternalError("fork failed");
  if (pid == 0) {
    // Only async-signal-safe calls between fork and exec.
    prctl(PR_SET_PDEATHSIG, SIGKILL);
    if (getppid() != parent) _exit(127);
    dup2(pipe_fds[1], STDOUT_FILENO);
    dup2(pipe_fds[1], STDERR_FILENO);
    execv(argv[0], argv.data());
    _exit(127);
  }
  close(pipe_fds[1]);
  std::unique_ptr<ServerProcess> server(new ServerProcess());
  server->pid_ = pid;
  server->pump_ = std::thread([s = server.get(), fd = pipe_fds[0]] { s->Pump(fd); });
  server->port_ = server->WaitForPort("listening on ");
  if (server->port_ == 0) {
    return absl::UnavailableError(
        absl::StrCat("tetrefine_server did not start; its log:\n", server->Log()));
  }
  // Logged before the gRPC port, so already there if the endpoint is on.
  server->metrics_port_ = server->WaitForPortNow("metrics on http://");
  return server;
}

ServerProcess::~ServerProcess() {
  if (!reaped_) {
    kill(pid_, SIGTERM);
    if (!Reap(10'000)) {
      kill(pid_, SIGKILL);
      Reap(10'000);
    }
  }
  if (pump_.joinable()) pump_.join();
}

void ServerProcess::Kill() {
  if (reaped_) return;
  kill(pid_, SIGKILL);
  Reap(10'000);
}

bool ServerProcess::Reap(int timeout_ms) {
  const Clock::time_point until = Clock::now() + std::chrono::milliseconds(timeout_ms);
  while (Clock::now() < until) {
    int status = 0;
    const pid_t r = waitpid(pid_, &status, WNOHANG);
    if (r == pid_ || r < 0) {
      reaped_ = true;
      return true;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  return false;
}

std::string ServerProcess::target() const { return absl::StrCat("127.0.0.1:", port_); }

std::string ServerProcess::Log() const {
  std::lock_guard<std::mutex> lock(mu_);
  return log_;
}

void ServerProcess::Pump(int fd) {
  char buffer[4096];
  for (;;) {
    const ssize_t n = read(fd, buffer, sizeof(buffer));
    if (n < 0 && errno == EINTR) continue;
    std::lock_guard<std::mutex> lock(mu_);
    if (n <= 0) {
      eof_ = true;
      changed_.notify_all();
      break;
    }
    log_.append(buffer, static_cast<size_t>(n));
    changed_.notify_all();
  }
  close(fd);
}

int ServerProcess::PortIn(const std::string& log, const std::string& prefix) {
  const std::regex pattern(prefix + "127\\.0\\.0\\.1:([0-9]+)");
  std::smatch match;
  if (!std::regex_search(log, match, pattern)) return 0;
  return std::atoi(match[1].str().c_str());
}

int ServerProcess::WaitForPort(const std::string& prefix) {
  std::unique_lock<std::mutex> lock(mu_);
  const Clock::time_point until = Clock::now() + std::chrono::seconds(30);
  for (;;) {
    if (const int port = PortIn(log_, prefix); port != 0) return port;
    if (eof_ || changed_.wait_until(lock, until) == std::cv_status::timeout) {
      return PortIn(log_, prefix);
    }
  }
}

int ServerProcess::WaitForPortNow(const std::string& prefix) {
  std::lock_guard<std::mutex> lock(mu_);
  return PortIn(log_, prefix);
}

absl::StatusOr<std::string> HttpGet(int port, const std::string& path) {
  const int fd = socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
  if (fd < 0) return absl::InternalError("socket failed");
  timeval timeout{.tv_sec = 10, .tv_usec = 0};
  setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &timeout, sizeof(timeout));
  setsockopt(fd, SOL_SOCKET, SO_SNDTIMEO, &timeout, sizeof(timeout));
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_port = htons(static_cast<uint16_t>(port));
  address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  if (connect(fd, reinterpret_cast<sockaddr*>(&address), sizeof(address)) != 0) {
    close(fd);
    return absl::UnavailableError(absl::StrCat("cannot connect to 127.0.0.1:", port));
  }
  // HTTP/1.0: the server closes the connection after the response, which ends the read loop.
  const std::string request = absl::StrCat("GET ", path, " HTTP/1.0\r\nHost: 127.0.0.1\r\n\r\n");
  if (send(fd, request.data(), request.size(), MSG_NOSIGNAL) !=
      static_cast<ssize_t>(request.size())) {
    close(fd);
    return absl::UnavailableError("send failed");
  }
  std::string response;
  char buffer[8192];
  for (;;) {
    const ssize_t n = recv(fd, buffer, sizeof(buffer), 0);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) {
      close(fd);
      return absl::DeadlineExceededError("no complete HTTP response within 10 s");
    }
    if (n == 0) break;
    response.append(buffer, static_cast<size_t>(n));
  }
  close(fd);
  const size_t body = response.find("\r\n\r\n");
  if (body == std::string::npos || response.size() < 12 || response.compare(0, 7, "HTTP/1.") != 0 ||
      response.compare(9, 3, "200") != 0) {
    return absl::InternalError(absl::StrCat("unexpected HTTP response: ", response.substr(0, 200)));
  }
  return response.substr(body + 4);
}

}  // namespace tetrefine::testing
