// The server's Prometheus endpoint: scraped over HTTP on loopback, its counters follow the calls.

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <sstream>
#include <string>
#include <thread>

#include "client/refine_client.h"
#include "grpcpp/create_channel.h"
#include "grpcpp/security/credentials.h"
#include "gtest/gtest.h"
#include "tests/support/geometry.h"
#include "tests/support/server_process.h"

namespace tetrefine::testing {
namespace {

// Samples of a text exposition by series ("name" or "name{labels}"); comments skipped.
std::map<std::string, double> ParseExposition(const std::string& text) {
  std::map<std::string, double> samples;
  std::istringstream lines(text);
  std::string line;
  while (std::getline(lines, line)) {
    if (line.empty() || line[0] == '#') continue;
    const size_t space = line.rfind(' ');
    if (space == std::string::npos) continue;
    samples[line.substr(0, space)] = std::stod(line.substr(space + 1));
  }
  return samples;
}

std::map<std::string, double> Scrape(const ServerProcess& server) {
  absl::StatusOr<std::string> body = HttpGet(server.metrics_port(), "/metrics");
  EXPECT_TRUE(body.ok()) << body.status();
  return body.ok() ? ParseExposition(*body) : std::map<std::string, double>{};
}

double Get(const std::map<std::string, double>& samples, const std::string& series) {
  const auto it = samples.find(series);
  EXPECT_NE(it, samples.end()) << "no series " << series;
  return it == samples.end() ? -1.0 : it->second;
}

std::unique_ptr<ServerProcess> StartServer(const std::vector<std::string>& flags) {
  absl::StatusOr<std::unique_ptr<ServerProcess>> server = ServerProcess::Start(flags);
  EXPECT_TRUE(server.ok()) << server.status();
  return server.ok() ? *std::move(server) : nullptr;
}

TEST(MetricsTest, CountersFollowRefineCalls) {
  std::unique_ptr<ServerProcess> server =
      StartServer({"--metrics_listen=127.0.0.1:0", "--max_input_tets=500"});
  ASSERT_NE(server, nullptr);
  ASSERT_NE(server->metrics_port(), 0) << server->Log();

  const std::map<std::string, double> before = Scrape(*server);
  EXPECT_EQ(Get(before, R"(tetrefine_refine_calls_total{code="OK"})"), 0.0);
  EXPECT_EQ(Get(before, "tetrefine_tets_in_total"), 0.0);
  EXPECT_EQ(Get(before, "tetrefine_refinements_in_flight"), 0.0);

  const Volume volume = TestVolume({12, 12, 12});
  const Mesh mesh = FiveTetMesh({1.0, 1.0, 1.0}, {10.0, 10.0, 10.0}, {3, 3, 3});
  client::RefineRequestOptions options;
  options.refine.epsilon = 0.02;
  options.refine.max_iterations = 3;
  auto channel = grpc::CreateChannel(server->target(), grpc::InsecureChannelCredentials());
  absl::StatusOr<client::ClientResult> ok =
      client::RefineViaService(channel, volume, mesh, options);
  ASSERT_TRUE(ok.ok()) << ok.status();
  options.refine.epsilon = -1.0;  // refused by the server: INVALID_ARGUMENT
  absl::StatusOr<client::ClientResult> refused =
      client::RefineViaService(channel, volume, mesh, options);
  ASSERT_EQ(refused.status().code(), absl::StatusCode::kInvalidArgument) << refused.status();
  // A mesh header over --max_input_tets: its declared count was added to tets_in (an operator
  // sweep put 1e15 there with one request).
  options.refine.epsilon = 0.02;
  const Mesh too_big = FiveTetMesh({1.0, 1.0, 1.0}, {10.0, 10.0, 10.0}, {6, 6, 6});
  absl::StatusOr<client::ClientResult> over =
      client::RefineViaService(channel, volume, too_big, options);
  ASSERT_EQ(over.status().code(), absl::StatusCode::kResourceExhausted) << over.status();

  const std::map<std::string, double> after = Scrape(*server);
  EXPECT_EQ(Get(after, R"(tetrefine_refine_calls_total{code="OK"})"), 1.0);
  EXPECT_EQ(Get(after, R"(tetrefine_refine_calls_total{code="INVALID_ARGUMENT"})"), 1.0);
  EXPECT_EQ(Get(after, R"(tetrefine_refine_calls_total{code="RESOURCE_EXHAUSTED"})"), 1.0);
  // The accepted call's tets; the refused ones fail on their options or mesh header.
  EXPECT_EQ(Get(after, "tetrefine_tets_in_total"), static_cast<double>(mesh.tets.size()));
  EXPECT_EQ(Get(after, "tetrefine_tets_out_total"),
            static_cast<double>(ok->result.mesh.tets.size()));
  EXPECT_GT(Get(after, "tetrefine_received_bytes_total"),
            static_cast<double>(volume.data().size()));
  EXPECT_EQ(Get(after, "tetrefine_refine_duration_seconds_count"), 3.0);
  EXPECT_GT(Get(after, "tetrefine_refine_duration_seconds_sum"), 0.0);
  EXPECT_EQ(Get(after, R"(tetrefine_refine_duration_seconds_bucket{le="+Inf"})"), 3.0);
  EXPECT_EQ(Get(after, "tetrefine_refinements_in_flight"), 0.0);
}

// A call cancelled during its refinement delivers no mesh: its tets are not output (they were
// counted, 37 M of them in one operator sweep).
TEST(MetricsTest, ACancelledCallAddsNoOutputTets) {
  std::unique_ptr<ServerProcess> server =
      StartServer({"--metrics_listen=127.0.0.1:0", "--threads=1"});
  ASSERT_NE(server, nullptr);
  const Volume volume = TestVolume({22, 22, 22});
  const Mesh mesh = FiveTetMesh({1.0, 1.0, 1.0}, {20.0, 20.0, 20.0}, {19, 19, 19});
  client::RefineRequestOptions options;
  options.refine.epsilon = 0.001;
  options.refine.max_iterations = 8;
  client::RefineCallbacks callbacks;
  std::atomic<bool> iterated{false};
  callbacks.on_iteration = [&](const IterationStats&) { iterated.store(true); };
  callbacks.should_cancel = [&] { return iterated.load(); };
  auto channel = grpc::CreateChannel(server->target(), grpc::InsecureChannelCredentials());
  absl::StatusOr<client::ClientResult> cancelled =
      client::RefineViaService(channel, volume, mesh, options, callbacks);
  ASSERT_EQ(cancelled.status().code(), absl::StatusCode::kCancelled) << cancelled.status();
  // The server finishes the call after the client has gone: wait for its status to be counted.
  std::map<std::string, double> after;
  for (int i = 0; i < 100; ++i) {
    after = Scrape(*server);
    if (after.count(R"(tetrefine_refine_calls_total{code="CANCELLED"})") > 0) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  EXPECT_EQ(Get(after, R"(tetrefine_refine_calls_total{code="CANCELLED"})"), 1.0);
  EXPECT_EQ(Get(after, "tetrefine_tets_in_total"), static_cast<double>(mesh.tets.size()));
  EXPECT_EQ(Get(after, "tetrefine_tets_out_total"), 0.0);
}

// Clients ask GetServerInfo before they refine, so a wrong token ends there: it is logged and
// counted (three refused CLI runs used to leave no trace on the server).
TEST(MetricsTest, RefusedIdentitiesAreLoggedAndCounted) {
  const std::string tokens = (std::filesystem::temp_directory_path() /
                              ("tetrefine_metrics_tokens_" + std::to_string(::getpid())))
                                 .string();
  std::ofstream(tokens) << "alice alice-token-0123456789abcdef\n";
  std::unique_ptr<ServerProcess> server =
      StartServer({"--metrics_listen=127.0.0.1:0", "--token_file=" + tokens});
  ASSERT_NE(server, nullptr);
  auto channel = grpc::CreateChannel(server->target(), grpc::InsecureChannelCredentials());
  const auto deadline = std::chrono::system_clock::now() + std::chrono::seconds(10);
  EXPECT_TRUE(client::GetServerInfo(channel, deadline, "alice-token-0123456789abcdef").ok());
  for (const char* token : {"wrong-token-0123456789abcdef", ""}) {
    EXPECT_EQ(client::GetServerInfo(channel, deadline, token).status().code(),
              absl::StatusCode::kUnauthenticated);
  }
  const std::map<std::string, double> after = Scrape(*server);
  EXPECT_EQ(Get(after, R"(tetrefine_server_info_calls_total{code="OK"})"), 1.0);
  EXPECT_EQ(Get(after, R"(tetrefine_server_info_calls_total{code="UNAUTHENTICATED"})"), 2.0);
  EXPECT_TRUE(server->process().WaitForLine("refused: UNAUTHENTICATED the bearer token is not",
                                            std::chrono::seconds(5)))
      << server->Log();
  std::filesystem::remove(tokens);
}

// Opens `count` connections to the metrics port that send half a request and then nothing.
std::vector<int> UnfinishedRequests(int port, int count) {
  std::vector<int> fds;
  for (int i = 0; i < count; ++i) {
    const int fd = socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
    sockaddr_in address{};
    address.sin_family = AF_INET;
    address.sin_port = htons(static_cast<uint16_t>(port));
    address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    EXPECT_EQ(connect(fd, reinterpret_cast<sockaddr*>(&address), sizeof(address)), 0);
    const std::string partial = "GET /metrics HTTP/1.1\r\nHost: 127.0.0.1\r\n";
    EXPECT_EQ(send(fd, partial.data(), partial.size(), MSG_NOSIGNAL),
              static_cast<ssize_t>(partial.size()));
    fds.push_back(fd);
  }
  return fds;
}

TEST(MetricsTest, UnfinishedRequestsDoNotKeepAScrapeOut) {
  std::unique_ptr<ServerProcess> server = StartServer({"--metrics_listen=127.0.0.1:0"});
  ASSERT_NE(server, nullptr);
  ASSERT_NE(server->metrics_port(), 0) << server->Log();
  // Two unfinished requests used to take both of civetweb's threads for 30 s. Now there are
  // four threads: a scrape beside two goes through at once.
  std::vector<int> slow = UnfinishedRequests(server->metrics_port(), 2);
  EXPECT_TRUE(HttpGet(server->metrics_port(), "/metrics").ok());
  // Beside six (more than the threads), it goes through once the endpoint has dropped the
  // unfinished ones after their 5 s request timeout: within HttpGet's own 10 s.
  std::vector<int> more = UnfinishedRequests(server->metrics_port(), 4);
  EXPECT_TRUE(HttpGet(server->metrics_port(), "/metrics").ok());
  for (int fd : slow) close(fd);
  for (int fd : more) close(fd);
}

TEST(MetricsTest, EmptyAddressDisablesTheEndpoint) {
  std::unique_ptr<ServerProcess> server = StartServer({"--metrics_listen="});
  ASSERT_NE(server, nullptr);
  EXPECT_EQ(server->metrics_port(), 0) << server->Log();
}

TEST(MetricsTest, BusyMetricsPortLeavesTheServiceUp) {
  std::unique_ptr<ServerProcess> first = StartServer({"--metrics_listen=127.0.0.1:0"});
  ASSERT_NE(first, nullptr);
  ASSERT_NE(first->metrics_port(), 0);
  std::unique_ptr<ServerProcess> second =
      StartServer({"--metrics_listen=127.0.0.1:" + std::to_string(first->metrics_port())});
  ASSERT_NE(second, nullptr);
  EXPECT_EQ(second->metrics_port(), 0);
  EXPECT_NE(second->Log().find("serving without metrics"), std::string::npos) << second->Log();
  auto channel = grpc::CreateChannel(second->target(), grpc::InsecureChannelCredentials());
  EXPECT_TRUE(client::GetServerInfo(channel).ok());
}

}  // namespace
}  // namespace tetrefine::testing
