// Faults against a real tetrefine_server process on loopback: clients that cancel, vanish or run
// out of time must free the server's work promptly (its CPU time stops growing within about a
// second); SIGTERM lets in-flight calls finish within the drain deadline and refuses new ones;
// a client retrying against a restarted server on the same port gets through.

#include <signal.h>

#include <atomic>
#include <chrono>
#include <cstdio>
#include <future>
#include <thread>
#include <vector>

#include "client/refine_client.h"
#include "gmock/gmock.h"
#include "gtest/gtest.h"
#include "tests/hardening/workloads.h"
#include "tests/support/child_process.h"
#include "tests/support/geometry.h"
#include "tests/support/server_process.h"
#include "tetrefine/v1/tetrefine.grpc.pb.h"
#include "wire/request_writer.h"

namespace tetrefine::hardening {
namespace {

using ::tetrefine::testing::ChildProcess;
using ::tetrefine::testing::FiveTetMesh;
using ::tetrefine::testing::NewUnsharedChannel;
using ::tetrefine::testing::ServerProcess;
using ::tetrefine::testing::TestVolume;
using ::tetrefine::testing::TimeUntilCpuIdle;

using Clock = std::chrono::steady_clock;
using std::chrono::milliseconds;
using ::testing::HasSubstr;

// The CPU time of a refining server grows by about a second a second; idle, by nothing. A window
// of 300 ms with under 30 ms of CPU time is idle.
constexpr milliseconds kIdleWindow{300};
// "Promptly": the core polls cancellation every few thousand tets and between iterations; the
// longest stretch without a poll (building the edge table of a few million tets) is well under a
// second in a release build. AddressSanitizer makes that stretch about three times longer.
#if defined(__SANITIZE_ADDRESS__)
constexpr milliseconds kPromptly{3000};
#else
constexpr milliseconds kPromptly{1000};
#endif
// How long after its deadline a client call may return, in wall time. The server's work is
// measured in CPU time (ExpectIdleSoon), which load does not stretch; the client's return is
// wall time, which it does: 1022 ms was seen once against a bound of kPromptly, with the
// refining server and the rest of a CI run on both cores. A client that ignored its deadline
// would wait for the whole refinement, which only cancellation ends early here (StartServer),
// so twice kPromptly still tells.
constexpr milliseconds kClientReturn = 2 * kPromptly;

// A short drain unless a test is about draining: these tests keep connections open, and a
// server with open connections takes the whole drain time to stop.
std::unique_ptr<ServerProcess> StartServer(std::vector<std::string> flags = {"--drain_seconds=2"}) {
  // The heavy workloads check every output tet on the lattice, far beyond the default caps:
  // work that only cancellation ends early is what these tests need.
  flags.insert(flags.end(), {"--max_lattice_n=64", "--max_lattice_points=1000000000000"});
  absl::StatusOr<std::unique_ptr<ServerProcess>> server = ServerProcess::Start(flags);
  EXPECT_TRUE(server.ok()) << server.status();
  return server.ok() ? *std::move(server) : nullptr;
}

// Waits until the server is clearly working: at least 0.15 s of CPU time within half a second
// (a refining server uses about a second a second; an idle one nothing). Bounded.
bool WaitUntilBusy(const ChildProcess& process) {
  const Clock::time_point end = Clock::now() + std::chrono::seconds(20);
  std::vector<double> samples;
  while (Clock::now() < end) {
    samples.push_back(process.CpuSeconds());
    if (samples.size() > 5 && samples.back() - samples[samples.size() - 6] >= 0.15) return true;
    std::this_thread::sleep_for(milliseconds(100));
  }
  return false;
}

void ExpectIdleSoon(ServerProcess& server, const char* after) {
  const milliseconds worked = TimeUntilCpuIdle(server.process(), kIdleWindow, milliseconds(10000));
  std::printf("[faults] server CPU idle %lld ms after %s\n", static_cast<long long>(worked.count()),
              after);
  std::fflush(stdout);
  EXPECT_LT(worked, kPromptly) << "the server kept working after " << after;
}

// The heavy workload's request messages.
std::vector<v1::RefineRequest> HeavyRequests() {
  const Workload& w = HeavyWorkload();
  std::vector<v1::RefineRequest> requests;
  wire::WriteRequest(w.options, w.volume, w.mesh, size_t{1} << 20, [&](const v1::RefineRequest& r) {
    requests.push_back(r);
    return true;
  });
  return requests;
}

TEST(HardeningFaultTest, CancelWhileSendingTheInput) {
  std::unique_ptr<ServerProcess> server = StartServer();
  ASSERT_NE(server, nullptr);
  const std::vector<v1::RefineRequest> requests = HeavyRequests();
  v1::Refiner::Stub stub(server->NewChannel());
  grpc::ClientContext context;
  auto stream = stub.Refine(&context);
  for (size_t i = 0; i < requests.size() / 2; ++i) ASSERT_TRUE(stream->Write(requests[i]));
  context.TryCancel();
  EXPECT_EQ(stream->Finish().error_code(), grpc::StatusCode::CANCELLED);
  EXPECT_TRUE(server->process().WaitForLine("status=CANCELLED", std::chrono::seconds(5)))
      << server->process().Output();
  ExpectIdleSoon(*server, "a cancel during the input");
  EXPECT_EQ(server->Stop(), 0);
}

TEST(HardeningFaultTest, CancelDuringTheRefinement) {
  std::unique_ptr<ServerProcess> server = StartServer();
  ASSERT_NE(server, nullptr);
  const Workload& w = HeavyWorkload();
  std::atomic<bool> iterated{false};
  client::RefineCallbacks callbacks;
  callbacks.on_iteration = [&](const IterationStats&) { iterated.store(true); };
  callbacks.should_cancel = [&] { return iterated.load(); };
  absl::StatusOr<client::ClientResult> result =
      client::RefineViaService(server->NewChannel(), w.volume, w.mesh, w.options, callbacks);
  EXPECT_EQ(result.status().code(), absl::StatusCode::kCancelled) << result.status();
  ExpectIdleSoon(*server, "a cancel during the refinement");
  EXPECT_TRUE(server->process().WaitForLine("status=CANCELLED", std::chrono::seconds(5)));
  EXPECT_EQ(server->Stop(), 0);
}

TEST(HardeningFaultTest, DeadlineExpiresDuringTheRefinement) {
  std::unique_ptr<ServerProcess> server = StartServer();
  ASSERT_NE(server, nullptr);
  const Workload& w = HeavyWorkload();
  std::atomic<bool> iterated{false};
  client::RefineCallbacks callbacks;
  callbacks.on_iteration = [&](const IterationStats&) { iterated.store(true); };
  client::CallOptions call;
  call.deadline = std::chrono::system_clock::now() + std::chrono::seconds(3);
  const auto deadline_steady = Clock::now() + std::chrono::seconds(3);
  absl::StatusOr<client::ClientResult> result =
      client::RefineViaService(server->NewChannel(), w.volume, w.mesh, w.options, callbacks, call);
  EXPECT_EQ(result.status().code(), absl::StatusCode::kDeadlineExceeded) << result.status();
  EXPECT_TRUE(iterated.load()) << "the deadline fell before the refinement got going";
  EXPECT_LT(Clock::now() - deadline_steady, kClientReturn) << "the client waited past its deadline";
  ExpectIdleSoon(*server, "the deadline");
  // The client's timer fires first and cancels the stream before the server's copy of the
  // deadline (set when the request arrived, so a little later) has passed: the server's log may
  // say either.
  const std::optional<std::string> logged =
      server->process().WaitForLine("Refine peer=", std::chrono::seconds(5));
  ASSERT_TRUE(logged.has_value()) << server->process().Output();
  EXPECT_THAT(*logged, ::testing::AnyOf(HasSubstr("status=DEADLINE_EXCEEDED"),
                                        HasSubstr("status=CANCELLED")));
  EXPECT_EQ(server->Stop(), 0);
}

TEST(HardeningFaultTest, ClientProcessKilledDuringTheRefinement) {
  std::unique_ptr<ServerProcess> server = StartServer();
  ASSERT_NE(server, nullptr);
  std::unique_ptr<ChildProcess> client =
      ChildProcess::Start({TETREFINE_REFINE_CLIENT_BINARY, server->target()});
  ASSERT_NE(client, nullptr);
  ASSERT_TRUE(client->WaitForLine("iteration 1", std::chrono::seconds(40))) << client->Output();
  ASSERT_TRUE(WaitUntilBusy(server->process()));
  client->Signal(SIGKILL);
  EXPECT_EQ(client->WaitExit(std::chrono::seconds(10)), 128 + SIGKILL);
  ExpectIdleSoon(*server, "the client process was killed");
  EXPECT_TRUE(server->process().WaitForLine("status=CANCELLED", std::chrono::seconds(5)))
      << server->process().Output();
  EXPECT_EQ(server->Stop(), 0);
}

TEST(HardeningFaultTest, CancelDuringTheLatticeVerification) {
  std::unique_ptr<ServerProcess> server = StartServer();
  ASSERT_NE(server, nullptr);
  // No iteration, so the work is all in the final lattice check: 135k tets at order 64 is
  // 6.5e9 samples, minutes of CPU unless cancellation reaches it.
  Workload w = HeavyWorkload();
  w.options.refine.max_iterations = 0;
  w.options.refine.lattice_n = 64;
  w.options.refine.lattice_max_tets = 10'000'000;
  std::atomic<bool> cancel{false};
  client::RefineCallbacks callbacks;
  callbacks.should_cancel = [&] { return cancel.load(); };
  std::future<absl::Status> call = std::async(std::launch::async, [&] {
    return client::RefineViaService(server->NewChannel(), w.volume, w.mesh, w.options, callbacks)
        .status();
  });
  // Whatever happens below, the client cancels before the future's destructor waits for it.
  struct CancelOnExit {
    std::atomic<bool>& cancel;
    ~CancelOnExit() { cancel.store(true); }
  } cancel_on_exit{cancel};
  ASSERT_TRUE(WaitUntilBusy(server->process()));
  std::this_thread::sleep_for(milliseconds(500));
  cancel.store(true);
  EXPECT_EQ(call.get().code(), absl::StatusCode::kCancelled);
  ExpectIdleSoon(*server, "a cancel during the lattice verification");
  EXPECT_EQ(server->Stop(), 0);
}

// One iteration that splits every edge of the heavy workload's 135k tets (to 1.08M): about half
// a second of refinement, with a deterministic result.
Workload MediumWorkload() {
  Workload w = HeavyWorkload();
  w.name = "medium";
  w.options.refine.max_iterations = 1;
  w.options.refine.lattice_n = 0;
  w.options.skip_final_mesh = false;
  return w;
}

TEST(HardeningFaultTest, SigtermLetsInFlightCallsFinishAndRefusesNewOnes) {
  const Workload w = MediumWorkload();
  const RefineResult expected = CoreResult(w);
  std::unique_ptr<ServerProcess> server = StartServer({"--drain_seconds=20", "--max_concurrent=4"});
  ASSERT_NE(server, nullptr);
  constexpr int kCalls = 4;
  std::atomic<int> started{0};
  std::vector<std::future<absl::StatusOr<client::ClientResult>>> calls;
  for (int i = 0; i < kCalls; ++i) {
    calls.push_back(std::async(std::launch::async, [&] {
      std::atomic<bool> counted{false};
      client::RefineCallbacks callbacks;
      callbacks.on_iteration = [&](const IterationStats&) {
        if (!counted.exchange(true)) started.fetch_add(1);
      };
      return client::RefineViaService(server->NewChannel(), w.volume, w.mesh, w.options, callbacks);
    }));
  }
  for (int i = 0; i < 3000 && started.load() < kCalls; ++i) {
    std::this_thread::sleep_for(milliseconds(10));
  }
  ASSERT_EQ(started.load(), kCalls) << "the calls did not all start";
  const Clock::time_point signalled = Clock::now();
  server->process().Signal(SIGTERM);
  int in_flight = 0;
  for (auto& c : calls) in_flight += c.wait_for(milliseconds(0)) != std::future_status::ready;
  // Otherwise this would not test draining: make the medium workload heavier.
  EXPECT_GT(in_flight, 0) << "every call had finished before the signal";
  ASSERT_TRUE(server->process().WaitForLine("draining", std::chrono::seconds(10)));

  // A new call is refused at once.
  client::CallOptions call;
  call.deadline = std::chrono::system_clock::now() + std::chrono::seconds(10);
  const Workload& small = SmallWorkloads()[0];
  const auto new_call_start = Clock::now();
  absl::StatusOr<client::ClientResult> refused = client::RefineViaService(
      NewUnsharedChannel(server->target()), small.volume, small.mesh, small.options, {}, call);
  EXPECT_EQ(refused.status().code(), absl::StatusCode::kUnavailable) << refused.status();
  EXPECT_THAT(std::string(refused.status().message()), HasSubstr("shutting down"));
  EXPECT_LT(Clock::now() - new_call_start, std::chrono::seconds(2));

  for (auto& c : calls) {
    absl::StatusOr<client::ClientResult> result = c.get();
    ASSERT_TRUE(result.ok()) << result.status() << "\n" << server->process().Output();
    EXPECT_EQ(ResultDifference(expected, result->result), "");
  }
  auto since_signal = [&] {
    return std::chrono::duration<double>(Clock::now() - signalled).count();
  };
  const double finished = since_signal();
  EXPECT_TRUE(server->process().WaitForLine("tetrefine_server stopped", std::chrono::seconds(20)));
  const double stopped = since_signal();
  // After "stopped", gRPC's own shutdown may take up to ~10 s more (grpc_shutdown joins an
  // executor thread asleep in a long epoll_wait): bounded, but not by the drain time.
  const std::optional<int> exit_code = server->process().WaitExit(std::chrono::seconds(40));
  EXPECT_EQ(exit_code, 0) << server->process().Output();
  std::printf(
      "[faults] SIGTERM with %d of %d calls in flight: all finished correctly %.2f s after the "
      "signal; the server logged stopped at %.2f s and exited at %.2f s\n",
      in_flight, kCalls, finished, stopped, since_signal());
}

// A client still reading a large response when the server drains must get all of it.
TEST(HardeningFaultTest, SigtermDrainDeliversTheWholeResponseToASlowReader) {
  Workload w = MediumWorkload();
  w.options.response_chunk_bytes = 64 << 10;
  std::unique_ptr<ServerProcess> server = StartServer({"--drain_seconds=20"});
  ASSERT_NE(server, nullptr);
  v1::Refiner::Stub stub(server->NewChannel());
  grpc::ClientContext context;
  context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(60));
  auto stream = stub.Refine(&context);
  wire::WriteRequest(w.options, w.volume, w.mesh, size_t{1} << 20,
                     [&](const v1::RefineRequest& r) { return stream->Write(r); });
  stream->WritesDone();
  int messages = 0;
  bool summary = false;
  for (v1::RefineResponse response; stream->Read(&response);) {
    if (++messages == 1) server->process().Signal(SIGTERM);
    summary = response.has_summary();
    std::this_thread::sleep_for(milliseconds(5));
  }
  const grpc::Status status = stream->Finish();
  std::printf("[faults] slow reader: %d messages, summary %d, status %d %s\n", messages, summary,
              status.error_code(), status.error_message().c_str());
  EXPECT_TRUE(status.ok()) << status.error_message();
  EXPECT_TRUE(summary);
  EXPECT_EQ(server->process().WaitExit(std::chrono::seconds(40)), 0);
}

TEST(HardeningFaultTest, DrainDeadlineCancelsWhatIsStillRunning) {
  std::unique_ptr<ServerProcess> server = StartServer({"--drain_seconds=1"});
  ASSERT_NE(server, nullptr);
  const Workload& w = HeavyWorkload();
  std::future<absl::Status> call = std::async(std::launch::async, [&] {
    return client::RefineViaService(server->NewChannel(), w.volume, w.mesh, w.options).status();
  });
  ASSERT_TRUE(WaitUntilBusy(server->process()));
  const Clock::time_point signalled = Clock::now();
  server->process().Signal(SIGTERM);
  EXPECT_EQ(server->process().WaitExit(std::chrono::seconds(10)), 0) << server->process().Output();
  EXPECT_LT(Clock::now() - signalled, std::chrono::seconds(1) + kPromptly + milliseconds(500));
  EXPECT_FALSE(call.get().ok());
}

TEST(HardeningFaultTest, ClientRetryingAgainstARestartedServerSucceeds) {
  const Workload& w = SmallWorkloads()[1];
  const RefineResult expected = CoreResult(w);
  std::unique_ptr<ServerProcess> first = StartServer();
  ASSERT_NE(first, nullptr);
  const int port = first->port();
  const std::shared_ptr<grpc::Channel> channel = first->NewChannel();
  ASSERT_TRUE(client::RefineViaService(channel, w.volume, w.mesh, w.options).ok());
  ASSERT_EQ(first->Stop(), 0);

  // While nothing listens, a fail-fast call is UNAVAILABLE; a waiting one gets through once the
  // server is back on the same port.
  client::CallOptions fail_fast;
  fail_fast.deadline = std::chrono::system_clock::now() + std::chrono::seconds(5);
  EXPECT_EQ(
      client::RefineViaService(channel, w.volume, w.mesh, w.options, {}, fail_fast).status().code(),
      absl::StatusCode::kUnavailable);
  client::CallOptions waiting;
  waiting.wait_for_ready = true;
  waiting.deadline = std::chrono::system_clock::now() + std::chrono::seconds(30);
  std::future<absl::StatusOr<client::ClientResult>> retry = std::async(std::launch::async, [&] {
    return client::RefineViaService(channel, w.volume, w.mesh, w.options, {}, waiting);
  });
  std::this_thread::sleep_for(milliseconds(500));
  absl::StatusOr<std::unique_ptr<ServerProcess>> second = ServerProcess::Start({}, port);
  ASSERT_TRUE(second.ok()) << second.status();
  const Clock::time_point restarted = Clock::now();
  absl::StatusOr<client::ClientResult> result = retry.get();
  ASSERT_TRUE(result.ok()) << result.status();
  std::printf("[faults] a waiting call got through %.2f s after the server restarted\n",
              std::chrono::duration<double>(Clock::now() - restarted).count());
  EXPECT_EQ(ResultDifference(expected, result->result), "");
  EXPECT_EQ((*second)->Stop(), 0);
}

}  // namespace
}  // namespace tetrefine::hardening
