#include "tests/client/cli_test_util.h"

#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <poll.h>
#include <signal.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <regex>

#include "client/io/mesh_io.h"
#include "client/io/nifti_writer.h"
#include "gtest/gtest.h"

namespace tetrefine::clitest {
namespace {

using Clock = std::chrono::steady_clock;

// Starts argv with stdout and stderr on pipes (the same pipe when `err_fd` is null).
int Spawn(const std::vector<std::string>& argv, const std::string& cwd, int* out_fd, int* err_fd) {
  int out_pipe[2], err_pipe[2];
  // Close-on-exec, so no other child (a server started earlier) holds a copy of these pipes.
  if (pipe2(out_pipe, O_CLOEXEC) != 0) return -1;
  if (err_fd != nullptr && pipe2(err_pipe, O_CLOEXEC) != 0) return -1;
  const pid_t pid = fork();
  if (pid == 0) {
    const int devnull = open("/dev/null", O_RDONLY);
    dup2(devnull, 0);
    dup2(out_pipe[1], 1);
    dup2(err_fd != nullptr ? err_pipe[1] : out_pipe[1], 2);
    close(out_pipe[0]);
    close(out_pipe[1]);
    if (err_fd != nullptr) {
      close(err_pipe[0]);
      close(err_pipe[1]);
    }
    if (!cwd.empty() && chdir(cwd.c_str()) != 0) _exit(127);
    std::vector<char*> args;
    for (const std::string& a : argv) args.push_back(const_cast<char*>(a.c_str()));
    args.push_back(nullptr);
    execv(args[0], args.data());
    _exit(127);
  }
  close(out_pipe[1]);
  *out_fd = out_pipe[0];
  if (err_fd != nullptr) {
    close(err_pipe[1]);
    *err_fd = err_pipe[0];
  }
  return pid;
}

int DecodeStatus(int status) {
  if (WIFEXITED(status)) return WEXITSTATUS(status);
  if (WIFSIGNALED(status)) return 128 + WTERMSIG(status);
  return -1;
}

}  // namespace

ProcessResult RunProcess(const std::vector<std::string>& argv, const std::string& cwd,
                         double timeout_seconds) {
  ProcessResult result;
  const auto start = Clock::now();
  int out_fd = -1, err_fd = -1;
  const int pid = Spawn(argv, cwd, &out_fd, &err_fd);
  if (pid < 0) {
    ADD_FAILURE() << "cannot start " << argv[0];
    return result;
  }
  const auto deadline = start + std::chrono::duration_cast<Clock::duration>(
                                    std::chrono::duration<double>(timeout_seconds));
  pollfd fds[2] = {{out_fd, POLLIN, 0}, {err_fd, POLLIN, 0}};
  std::string* sinks[2] = {&result.out, &result.err};
  int open_fds = 2;
  while (open_fds > 0) {
    const auto left =
        std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now());
    if (left.count() <= 0) {
      result.timed_out = true;
      kill(pid, SIGKILL);
      break;
    }
    if (poll(fds, 2, static_cast<int>(left.count())) < 0) continue;
    for (int i = 0; i < 2; ++i) {
      if (fds[i].fd < 0 || fds[i].revents == 0) continue;
      char buffer[4096];
      const ssize_t n = read(fds[i].fd, buffer, sizeof(buffer));
      if (n > 0) {
        sinks[i]->append(buffer, static_cast<size_t>(n));
      } else {
        close(fds[i].fd);
        fds[i].fd = -1;
        --open_fds;
      }
    }
  }
  for (const pollfd& f : fds) {
    if (f.fd >= 0) close(f.fd);
  }
  int status = 0;
  waitpid(pid, &status, 0);
  result.exit_code = DecodeStatus(status);
  result.seconds = std::chrono::duration<double>(Clock::now() - start).count();
  return result;
}

ProcessResult RunTetrefine(const std::vector<std::string>& args, const std::string& cwd,
                           double timeout_seconds) {
  std::vector<std::string> argv = {TETREFINE_CLI_PATH};
  argv.insert(argv.end(), args.begin(), args.end());
  return RunProcess(argv, cwd, timeout_seconds);
}

std::vector<std::string> Lines(const std::string& text) {
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

ServerProcess::ServerProcess(const std::vector<std::string>& extra_flags) {
  std::vector<std::string> argv = {TETREFINE_SERVER_PATH, "--listen=127.0.0.1:0"};
  argv.insert(argv.end(), extra_flags.begin(), extra_flags.end());
  pid_ = Spawn(argv, "", &fd_, nullptr);
  if (pid_ < 0) return;
  // Port 0 lets the server pick a free port; it logs the one it bound.
  const std::regex listening(R"(listening on 127\.0\.0\.1:(\d+))");
  const auto deadline = Clock::now() + std::chrono::seconds(30);
  while (port_ == 0 && Clock::now() < deadline) {
    pollfd fd = {fd_, POLLIN, 0};
    if (poll(&fd, 1, 200) <= 0) continue;
    char buffer[4096];
    const ssize_t n = read(fd_, buffer, sizeof(buffer));
    if (n <= 0) break;  // the server exited
    startup_log_.append(buffer, static_cast<size_t>(n));
    std::smatch match;
    if (std::regex_search(startup_log_, match, listening)) port_ = std::stoi(match[1]);
  }
  const int fd = fd_;
  drain_ = std::thread([fd] {
    char buffer[4096];
    while (read(fd, buffer, sizeof(buffer)) > 0) {
    }
  });
}

ServerProcess::~ServerProcess() {
  if (pid_ > 0) {
    kill(pid_, SIGTERM);
    int status = 0;
    const auto deadline = Clock::now() + std::chrono::seconds(20);
    bool exited = false;
    while (Clock::now() < deadline) {
      if (waitpid(pid_, &status, WNOHANG) == pid_) {
        exited = true;
        break;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    if (!exited) {
      kill(pid_, SIGKILL);
      waitpid(pid_, &status, 0);
    }
  }
  // The child is gone, so the pipe reports end of file and the drain thread ends.
  if (drain_.joinable()) drain_.join();
  if (fd_ >= 0) close(fd_);
}

std::string ServerProcess::log() const { return startup_log_; }

int ClosedPort() {
  const int s = socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in address = {};
  address.sin_family = AF_INET;
  address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  address.sin_port = 0;
  bind(s, reinterpret_cast<sockaddr*>(&address), sizeof(address));
  socklen_t length = sizeof(address);
  getsockname(s, reinterpret_cast<sockaddr*>(&address), &length);
  const int port = ntohs(address.sin_port);
  close(s);
  return port;
}

Volume BumpVolume(const Index3& dims, const Vec3& origin, const Vec3& spacing) {
  const GridGeometry grid{dims, origin, spacing};
  Vec3 center;
  double radius = 0.0;
  for (int a = 0; a < 3; ++a) {
    center[a] = origin[a] + 0.5 * static_cast<double>(dims[a] - 1) * spacing[a];
    radius = std::max(radius, 0.3 * static_cast<double>(dims[a] - 1) * spacing[a]);
  }
  std::vector<double> values;
  values.reserve(static_cast<size_t>(dims[0] * dims[1] * dims[2]));
  for (int64_t k = 0; k < dims[2]; ++k) {
    for (int64_t j = 0; j < dims[1]; ++j) {
      for (int64_t i = 0; i < dims[0]; ++i) {
        const Vec3 p = {origin[0] + static_cast<double>(i) * spacing[0],
                        origin[1] + static_cast<double>(j) * spacing[1],
                        origin[2] + static_cast<double>(k) * spacing[2]};
        double r2 = 0.0;
        for (int a = 0; a < 3; ++a) r2 += (p[a] - center[a]) * (p[a] - center[a]);
        values.push_back(100.0 * std::exp(-r2 / (radius * radius)) + 0.5 * p[0]);
      }
    }
  }
  return *Volume::FromDoubles(grid, values);
}

void WriteVolume(const std::string& path, const Volume& volume) {
  const absl::Status status = io::WriteNifti(path, volume);
  ASSERT_TRUE(status.ok()) << status;
}

void WriteMeshFile(const std::string& path, const Mesh& mesh) {
  io::MeshFile file{.mesh = mesh, .tet_iteration = {}, .tet_quality = {}};
  const absl::Status status = io::WriteMesh(path, file);
  ASSERT_TRUE(status.ok()) << status;
}

bool FileExists(const std::string& path) {
  std::error_code ec;
  return std::filesystem::exists(path, ec);
}

}  // namespace tetrefine::clitest
