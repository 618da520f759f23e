#include "tests/hardening/server_process.h"

#include <signal.h>

#include <atomic>
#include <regex>

namespace tetrefine::hardening {

std::unique_ptr<ServerProcess> ServerProcess::Start(const std::vector<std::string>& flags, int port,
                                                    std::string* error,
                                                    int64_t address_space_bytes) {
  std::vector<std::string> argv;
  if (address_space_bytes > 0) {
    // prlimit sets the limit and execs the server, which keeps prlimit's pid.
    argv = {"/usr/bin/prlimit", "--as=" + std::to_string(address_space_bytes), "--"};
  }
  // Metrics on loopback too, on a port of their own: tests never listen beyond this host.
  argv.insert(argv.end(), {TETREFINE_SERVER_BINARY, "--listen=127.0.0.1:" + std::to_string(port),
                           "--metrics_listen=127.0.0.1:0"});
  argv.insert(argv.end(), flags.begin(), flags.end());
  auto server = std::make_unique<ServerProcess>();
  server->process_ = ChildProcess::Start(argv);
  if (server->process_ == nullptr) {
    if (error != nullptr) *error = "cannot start " + argv[0];
    return nullptr;
  }
  const std::optional<std::string> line =
      server->process_->WaitForLine("listening on 127.0.0.1:", std::chrono::seconds(30));
  std::smatch match;
  static const std::regex kListening(R"(listening on 127\.0\.0\.1:(\d+))");
  if (!line.has_value() || !std::regex_search(*line, match, kListening)) {
    if (error != nullptr) *error = "tetrefine_server did not start:\n" + server->process_->Output();
    return nullptr;
  }
  server->port_ = std::stoi(match[1].str());
  return server;
}

std::shared_ptr<grpc::Channel> NewUnsharedChannel(const std::string& target) {
  static std::atomic<int> channels{0};
  grpc::ChannelArguments args;
  args.SetInt("tetrefine.hardening.channel", channels.fetch_add(1));
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

}  // namespace tetrefine::hardening
