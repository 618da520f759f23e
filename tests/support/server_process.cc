#include "tests/support/server_process.h"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <signal.h>
#include <sys/socket.h>
#include <sys/time.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <regex>

#include "absl/status/status.h"
#include "absl/strings/str_cat.h"

namespace tetrefine::testing {
namespace {

// The port in the first "<prefix>127.0.0.1:<port>" of `text`, or 0.
int PortIn(const std::string& text, const std::string& prefix) {
  const std::regex pattern(prefix + R"(127\.0\.0\.1:(\d+))");
  std::smatch match;
  if (!std::regex_search(text, match, pattern)) return 0;
  return std::stoi(match[1].str());
}

}  // namespace

absl::StatusOr<std::unique_ptr<ServerProcess>> ServerProcess::Start(
    const std::vector<std::string>& flags, int port, int64_t address_space_bytes) {
  std::vector<std::string> argv;
  if (address_space_bytes > 0) {
    // prlimit sets the limit and execs the server, which keeps prlimit's pid.
    argv = {"/usr/bin/prlimit", "--as=" + std::to_string(address_space_bytes), "--"};
  }
  argv.insert(argv.end(), {TETREFINE_SERVER_BINARY, "--listen=127.0.0.1:" + std::to_string(port),
                           "--metrics_listen=127.0.0.1:0"});
  argv.insert(argv.end(), flags.begin(), flags.end());
  std::unique_ptr<ServerProcess> server(new ServerProcess());
  server->process_ = ChildProcess::Start(argv);
  if (server->process_ == nullptr) return absl::InternalError("cannot start " + argv[0]);
  const std::optional<std::string> line =
      server->process_->WaitForLine("listening on 127.0.0.1:", std::chrono::seconds(30));
  server->port_ = line.has_value() ? PortIn(*line, "listening on ") : 0;
  if (server->port_ == 0) {
    return absl::UnavailableError(
        absl::StrCat("tetrefine_server did not start; its output:\n", server->Log()));
  }
  // Logged before the gRPC port, so already there if the endpoint is on.
  server->metrics_port_ = PortIn(server->Log(), "metrics on http://");
  return server;
}

ServerProcess::~ServerProcess() {
  if (!Stop(std::chrono::seconds(10)).has_value()) Kill();
}

std::shared_ptr<grpc::Channel> NewUnsharedChannel(const std::string& target) {
  static std::atomic<int> channels{0};
  grpc::ChannelArguments args;
  args.SetInt("tetrefine.test.channel", channels.fetch_add(1));
  return grpc::CreateCustomChannel(target, grpc::InsecureChannelCredentials(), args);
}

std::shared_ptr<grpc::Channel> ServerProcess::NewChannel() const {
  std::shared_ptr<grpc::Channel> channel = NewUnsharedChannel(target());
  channel->WaitForConnected(std::chrono::system_clock::now() + std::chrono::seconds(10));
  return channel;
}

std::optional<int> ServerProcess::Stop(std::chrono::milliseconds timeout) {
  process_->Signal(SIGTERM);
  return process_->WaitExit(timeout);
}

void ServerProcess::Kill() {
  process_->Signal(SIGKILL);
  process_->WaitExit(std::chrono::seconds(10));
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
