// tetrefine_server as a process, against clients that are not all friendly: more idle or
// never-reading streams than refinement slots, repeated signals during a drain; and the binary's
// own command line (--help, errors on stderr).

#include <signal.h>

#include <atomic>
#include <chrono>
#include <cstdio>
#include <future>
#include <string>
#include <thread>
#include <vector>

#include "absl/strings/match.h"
#include "client/refine_client.h"
#include "gmock/gmock.h"
#include "gtest/gtest.h"
#include "tests/hardening/workloads.h"
#include "tests/support/child_process.h"
#include "tests/support/result_compare.h"
#include "tests/support/server_process.h"
#include "tetrefine/v1/tetrefine.grpc.pb.h"
#include "wire/request_writer.h"

namespace tetrefine::hardening {
namespace {

using ::testing::HasSubstr;
using ::testing::Not;
using ::tetrefine::testing::ChildProcess;
using ::tetrefine::testing::ProcessResult;
using ::tetrefine::testing::RunProcess;
using ::tetrefine::testing::ServerProcess;
using Clock = std::chrono::steady_clock;
using std::chrono::milliseconds;
using Stream = grpc::ClientReaderWriter<v1::RefineRequest, v1::RefineResponse>;

// A Refine stream a test drives by hand.
struct OpenStream {
  explicit OpenStream(const std::shared_ptr<grpc::Channel>& channel) : stub(channel) {
    context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(120));
    stream = stub.Refine(&context);
  }
  grpc::Status Finish() {
    for (v1::RefineResponse response; stream->Read(&response);) {
    }
    return stream->Finish();
  }
  v1::Refiner::Stub stub;
  grpc::ClientContext context;
  std::unique_ptr<Stream> stream;
};

std::vector<v1::RefineRequest> RequestsOf(const Workload& w) {
  std::vector<v1::RefineRequest> requests;
  wire::WriteRequest(w.options, w.volume, w.mesh, size_t{1} << 20, [&](const v1::RefineRequest& r) {
    requests.push_back(r);
    return true;
  });
  return requests;
}

const Workload& BigResult() {
  static const Workload* w = new Workload(BigResultWorkload());
  return *w;
}

std::unique_ptr<ServerProcess> Start(const std::vector<std::string>& flags) {
  absl::StatusOr<std::unique_ptr<ServerProcess>> server = ServerProcess::Start(flags);
  EXPECT_TRUE(server.ok()) << server.status();
  return server.ok() ? *std::move(server) : nullptr;
}

TEST(AbuseTest, EightIdleStreamsAndFourSlotsStillServeAGoodClient) {
  std::unique_ptr<ServerProcess> server = Start({"--max_concurrent=4", "--input_deadline_seconds=6",
                                                 "--idle_timeout_seconds=4", "--drain_seconds=2"});
  ASSERT_NE(server, nullptr);
  const Workload& good = SmallWorkloads()[0];
  const RefineResult expected = CoreResult(good);

  // Eight streams on one connection that open and send nothing, as a hostile or broken client
  // might; before issue 14 four of them took every slot until the client let go.
  const std::shared_ptr<grpc::Channel> hostile = server->NewChannel();
  std::vector<std::unique_ptr<OpenStream>> idle;
  for (int i = 0; i < 8; ++i) idle.push_back(std::make_unique<OpenStream>(hostile));
  std::this_thread::sleep_for(milliseconds(300));

  const Clock::time_point start = Clock::now();
  absl::StatusOr<client::ClientResult> result =
      client::RefineViaService(server->NewChannel(), good.volume, good.mesh, good.options);
  const double served = std::chrono::duration<double>(Clock::now() - start).count();
  ASSERT_TRUE(result.ok()) << result.status();
  EXPECT_EQ(ResultDifference(expected, result->result), "");
  EXPECT_LT(served, 6.0) << "not served within the input deadline";
  std::printf("[abuse] 8 idle streams, 4 slots: a good client was served in %.3f s\n", served);

  for (auto& stream : idle) {
    const grpc::Status status = stream->Finish();
    EXPECT_EQ(status.error_code(), grpc::StatusCode::DEADLINE_EXCEEDED) << status.error_message();
    EXPECT_THAT(status.error_message(), HasSubstr("--idle_timeout_seconds"));
  }
  EXPECT_EQ(server->Stop(), 0) << server->process().Output();
}

TEST(AbuseTest, EightNeverReadingClientsAndFourSlotsStillServeAGoodClient) {
  std::unique_ptr<ServerProcess> server =
      Start({"--max_concurrent=4", "--write_stall_seconds=3", "--input_deadline_seconds=20",
             "--queue_seconds=30", "--drain_seconds=2"});
  ASSERT_NE(server, nullptr);
  const std::vector<v1::RefineRequest> requests = RequestsOf(BigResult());
  // Eight clients send a whole request whose result is megabytes, and never read a byte of it.
  std::vector<std::unique_ptr<OpenStream>> never_read;
  for (int i = 0; i < 8; ++i) {
    never_read.push_back(std::make_unique<OpenStream>(server->NewChannel()));
    for (const v1::RefineRequest& r : requests) ASSERT_TRUE(never_read.back()->stream->Write(r));
    ASSERT_TRUE(never_read.back()->stream->WritesDone());
  }
  const Workload& good = SmallWorkloads()[1];
  const RefineResult expected = CoreResult(good);
  const Clock::time_point start = Clock::now();
  absl::StatusOr<client::ClientResult> result =
      client::RefineViaService(server->NewChannel(), good.volume, good.mesh, good.options);
  const double served = std::chrono::duration<double>(Clock::now() - start).count();
  ASSERT_TRUE(result.ok()) << result.status();
  EXPECT_EQ(ResultDifference(expected, result->result), "");
  EXPECT_LT(served, 20.0) << "not served within the input deadline";
  std::printf("[abuse] 8 never-reading clients, 4 slots: a good client was served in %.3f s\n",
              served);
  // Each never-reading call is cancelled by the server once a response has waited 3 s for it
  // (the clients are not read from until then: reading would let them go on).
  auto stalled = [&] {
    int n = 0;
    for (const std::string& line : server->process().Lines()) {
      n += absl::StrContains(line, "the client stopped reading; cancelling the call");
    }
    return n;
  };
  for (int i = 0; i < 600 && stalled() < 8; ++i) std::this_thread::sleep_for(milliseconds(50));
  EXPECT_EQ(stalled(), 8) << server->process().Output();
  for (auto& stream : never_read) {
    EXPECT_EQ(stream->Finish().error_code(), grpc::StatusCode::CANCELLED);
  }
  EXPECT_EQ(server->Stop(), 0) << server->process().Output();
}

// Two iterations on 135k tets towards 8.6M: a few seconds of refinement to send signals into.
Workload DrainWorkload() {
  Workload w = HeavyWorkload();
  w.name = "drain";
  w.options.refine.max_iterations = 2;
  w.options.refine.lattice_n = 0;
  w.options.skip_final_mesh = true;
  return w;
}

TEST(AbuseTest, SignalsDuringTheDrainAreLoggedAndIgnored) {
  const Workload w = DrainWorkload();
  const RefineResult expected = CoreResult(w);
  std::unique_ptr<ServerProcess> server = Start({"--drain_seconds=60"});
  ASSERT_NE(server, nullptr);
  std::atomic<bool> iterating{false};
  std::future<absl::StatusOr<client::ClientResult>> call = std::async(std::launch::async, [&] {
    client::RefineCallbacks callbacks;
    callbacks.on_iteration = [&](const IterationStats&) { iterating.store(true); };
    return client::RefineViaService(server->NewChannel(), w.volume, w.mesh, w.options, callbacks);
  });
  for (int i = 0; i < 6000 && !iterating.load(); ++i) std::this_thread::sleep_for(milliseconds(5));
  ASSERT_TRUE(iterating.load()) << server->process().Output();

  server->process().Signal(SIGTERM);
  ASSERT_TRUE(server->process().WaitForLine("draining", std::chrono::seconds(10)));
  // Readiness (the Refiner) goes NOT_SERVING; liveness (the server, "") stays SERVING, or an
  // orchestrator would kill the process in the middle of its drain.
  const auto soon = std::chrono::system_clock::now() + std::chrono::seconds(5);
  EXPECT_EQ(client::CheckHealth(server->NewChannel(), "tetrefine.v1.Refiner", soon)
                .value_or(client::ServingStatus::kUnknown),
            client::ServingStatus::kNotServing);
  EXPECT_EQ(
      client::CheckHealth(server->NewChannel(), "", soon).value_or(client::ServingStatus::kUnknown),
      client::ServingStatus::kServing);
  // An impatient operator: Ctrl-C twice, SIGTERM three more times, then closes the terminal.
  for (int s : {SIGINT, SIGINT, SIGTERM, SIGTERM, SIGTERM, SIGHUP}) {
    server->process().Signal(s);
    std::this_thread::sleep_for(milliseconds(30));
  }
  absl::StatusOr<client::ClientResult> result = call.get();
  ASSERT_TRUE(result.ok()) << result.status() << "\n" << server->process().Output();
  // The final mesh is not sent (skip_final_mesh): the statistics must be the core's.
  ASSERT_EQ(result->result.iterations.size(), expected.iterations.size());
  for (size_t i = 0; i < expected.iterations.size(); ++i) {
    ::tetrefine::testing::ExpectSameStats(expected.iterations[i], result->result.iterations[i]);
  }
  EXPECT_EQ(result->result.stop_reason, expected.stop_reason);
  EXPECT_EQ(server->process().WaitExit(std::chrono::seconds(60)), 0) << server->process().Output();
  int ignored = 0;
  for (const std::string& line : server->process().Lines()) {
    ignored += absl::StrContains(line, "again while draining: ignored");
  }
  EXPECT_EQ(ignored, 6) << server->process().Output();
}

// A call with default options (32 iterations, no max_tets) reserves the server's default tet
// budget; that budget must leave room in the memory budget for the call's own input (it did not:
// such calls were refused as needing more than the whole budget).
TEST(AbuseTest, ACallWithDefaultOptionsFitsTheDefaultBudget) {
  std::unique_ptr<ServerProcess> server =
      Start({"--memory_limit_bytes=1073741824", "--drain_seconds=2"});
  ASSERT_NE(server, nullptr);
  Workload w = SmallWorkloads()[0];
  w.options = {};  // defaults: epsilon 0.1, 32 iterations, the server's tet budget
  absl::StatusOr<client::ClientResult> result =
      client::RefineViaService(server->NewChannel(), w.volume, w.mesh, w.options);
  EXPECT_TRUE(result.ok()) << result.status();
  EXPECT_EQ(server->Stop(), 0) << server->process().Output();
}

// The default tet budget is one that --max_concurrent calls reserve together: it was one call's
// 90% of the memory budget, so on a 24 GiB machine two calls with default options held the
// whole budget and a third, of one tet, waited its queue time and was refused (a service sweep).
TEST(AbuseTest, TheDefaultTetBudgetLetsMaxConcurrentCallsRunTogether) {
  for (const int concurrent : {1, 4}) {
    SCOPED_TRACE(concurrent);
    std::unique_ptr<ServerProcess> server =
        Start({"--memory_limit_bytes=4294967296", "--drain_seconds=0",
               "--max_concurrent=" + std::to_string(concurrent)});
    ASSERT_NE(server, nullptr);
    absl::StatusOr<client::ServerInfo> info = client::GetServerInfo(server->NewChannel());
    ASSERT_TRUE(info.ok()) << info.status();
    const wire::ServiceLimits& l = info->limits;
    ASSERT_EQ(l.max_concurrent_refinements, concurrent);
    // Each call: two messages in flight and its budget's tets, a tenth of the budget left over
    // for the inputs.
    const int64_t call = 2 * l.max_message_bytes + l.max_output_tets * l.bytes_per_output_tet;
    EXPECT_LE(concurrent * call, l.memory_budget_bytes / 10 * 9);
    // And not needlessly small: one tet's bytes more per call would not fit.
    EXPECT_GT(concurrent * (call + concurrent * l.bytes_per_output_tet),
              l.memory_budget_bytes / 10 * 9);
    EXPECT_EQ(server->Stop(), 0) << server->process().Output();
  }
}

TEST(ServerCommandLineTest, HelpListsTheFlagsWithTheirDefaults) {
  const ProcessResult help = RunProcess({TETREFINE_SERVER_BINARY, "--help"}, "", 30.0);
  const std::string text = help.out + help.err;
  EXPECT_THAT(text, Not(HasSubstr("No flags matched")));
  for (const char* flag : {"--listen",
                           "--local_listen",
                           "--metrics_listen",
                           "--max_concurrent",
                           "--queue_seconds",
                           "--input_deadline_seconds",
                           "--idle_timeout_seconds",
                           "--write_stall_seconds",
                           "--max_call_seconds",
                           "--max_calls_per_identity",
                           "--max_iterations",
                           "--max_lattice_n",
                           "--max_lattice_points",
                           "--memory_limit_bytes",
                           "--memory_budget_bytes",
                           "--bytes_per_output_tet",
                           "--token_file",
                           "--tls_allowed_subjects",
                           "--reflection",
                           "--keepalive_seconds",
                           "--drain_seconds"}) {
    EXPECT_THAT(text, HasSubstr(flag));
  }
  // /metrics stays on this host unless asked otherwise.
  EXPECT_THAT(text, HasSubstr("default: \"127.0.0.1:9464\""));
}

TEST(ServerCommandLineTest, StartupErrorsGoToStderrNamingTheFlag) {
  struct Case {
    std::vector<std::string> flags;
    std::string message;
  };
  for (const Case& c : std::vector<Case>{
           {{"--max_concurrent=0"}, "--max_concurrent: must be >= 1, got 0"},
           {{"--threads=-1"}, "--threads: must be >= 0, got -1"},
           {{"--token_file=/tmp"}, "--token_file: /tmp: is a directory, not a token file"},
           {{"--token_file=/nonexistent/tokens"}, "--token_file: /nonexistent/tokens: cannot read"},
           {{"--local_listen=0.0.0.0:0"}, "--local_listen=0.0.0.0:0: must be a loopback address"},
           {{"--tls_cert=/nonexistent/cert.pem", "--tls_key=/nonexistent/key.pem"},
            "--tls_cert: cannot read /nonexistent/cert.pem"},
           {{"--tls_allowed_subjects=CN=a"}, "--tls_allowed_subjects needs --tls_client_ca"},
           {{"--max_lattice_n=65"}, "--max_lattice_n: must be in [0, 64]"},
           {{"--idle_timeout_seconds=0"}, "--idle_timeout_seconds: must be > 0"},
           {{"--log_level=chatty"}, "unknown --log_level chatty"},
           // gRPC took port 99999 as 34463, and a bare metrics port bound every interface.
           {{"--listen=127.0.0.1:99999"},
            "--listen=127.0.0.1:99999: expected host:port with a port 0-65535"},
           {{"--local_listen=127.0.0.1:65536"}, "--local_listen=127.0.0.1:65536: expected"},
           {{"--metrics_listen=52254"}, "--metrics_listen=52254: expected host:port"},
           // About 9.2e9 s overflows the clocks: every call then failed at once.
           {{"--max_call_seconds=1e10"}, "--max_call_seconds: must be > 0 and at most 1e9 s"},
           {{"--drain_seconds=1e10"}, "--drain_seconds: must be >= 0 and at most 1e9 s"},
           {{"--queue_seconds=inf"}, "--queue_seconds: must be >= 0 and at most 1e9 s"},
           // A tet budget no call can reserve, and a budget of a few MiB.
           {{"--memory_limit_bytes=1000000000", "--max_output_tets=20000000"},
            "--max_output_tets=20000000: a call that reaches it needs 3.0 GiB (160 bytes a tet, "
            "--bytes_per_output_tet), more than the memory budget of 697.7 MiB (from "
            "--memory_limit_bytes): at most 4519849 fit"},
           {{"--memory_limit_bytes=277000000"},
            "the memory budget (8.2 MiB, from --memory_limit_bytes) leaves room for 0 output tets"},
       }) {
    std::vector<std::string> argv = {TETREFINE_SERVER_BINARY, "--listen=127.0.0.1:0",
                                     "--metrics_listen="};
    argv.insert(argv.end(), c.flags.begin(), c.flags.end());
    const ProcessResult run = RunProcess(argv, "", 30.0);
    EXPECT_EQ(run.exit_code, 2) << c.flags[0] << "\n" << run.err;
    EXPECT_THAT(run.err, HasSubstr(c.message));
    EXPECT_EQ(run.out, "") << c.flags[0];
  }
}

// gRPC bound with SO_REUSEPORT: a second server on a port in use started, and new connections
// went to either at random. It is now refused, naming the address.
TEST(ServerCommandLineTest, APortInUseIsRefused) {
  absl::StatusOr<std::unique_ptr<ServerProcess>> first =
      ServerProcess::Start({"--drain_seconds=1"});
  ASSERT_TRUE(first.ok()) << first.status();
  const std::string target = (*first)->target();
  const ProcessResult second = RunProcess(
      {TETREFINE_SERVER_BINARY, "--listen=" + target, "--metrics_listen=", "--drain_seconds=0"}, "",
      30.0);
  EXPECT_EQ(second.exit_code, 1) << second.err;
  EXPECT_THAT(second.err, HasSubstr("cannot listen on " + target + ": the port is in use"));
  EXPECT_EQ((*first)->Stop(), 0) << (*first)->process().Output();
}

// SIGHUP (a closed terminal) killed the server at once, cutting off its calls; it drains as
// SIGTERM does, and exits 0.
TEST(ServerCommandLineTest, SighupDrainsLikeSigterm) {
  std::unique_ptr<ServerProcess> server = Start({"--drain_seconds=5"});
  ASSERT_NE(server, nullptr);
  server->process().Signal(SIGHUP);
  ASSERT_TRUE(server->process().WaitForLine("draining", std::chrono::seconds(10)))
      << server->process().Output();
  EXPECT_EQ(server->process().WaitExit(std::chrono::seconds(30)), 0) << server->process().Output();
}

// Under nohup (SIGHUP ignored from the start) a closed terminal must not stop the server: it
// blocked SIGHUP for its signal thread, which queued it whatever its disposition, and drained
// (found by a read-through, 2026-11-29).
TEST(ServerCommandLineTest, SighupIgnoredUnderNohupStaysIgnored) {
  std::unique_ptr<ChildProcess> server =
      ChildProcess::Start({"/usr/bin/nohup", TETREFINE_SERVER_BINARY, "--listen=127.0.0.1:0",
                           "--metrics_listen=", "--drain_seconds=1"});
  ASSERT_NE(server, nullptr);
  ASSERT_TRUE(server->WaitForLine("listening on 127.0.0.1:", std::chrono::seconds(30)))
      << server->Output();
  server->Signal(SIGHUP);
  EXPECT_FALSE(server->WaitExit(std::chrono::seconds(2)).has_value()) << server->Output();
  EXPECT_FALSE(absl::StrContains(server->Output(), "draining")) << server->Output();
  server->Signal(SIGTERM);
  ASSERT_TRUE(server->WaitForLine("draining", std::chrono::seconds(10))) << server->Output();
  EXPECT_EQ(server->WaitExit(std::chrono::seconds(30)), 0) << server->Output();
}

}  // namespace
}  // namespace tetrefine::hardening
