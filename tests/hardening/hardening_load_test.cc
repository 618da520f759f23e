// Load against a real tetrefine_server process on loopback: many concurrent clients, every
// result checked against core Refine, latency reported, memory watched across rounds, and the
// concurrency limit refusing the excess quickly instead of the server growing.

#include <atomic>
#include <chrono>
#include <cstdio>
#include <thread>
#include <vector>

#include "client/refine_client.h"
#include "gtest/gtest.h"
#include "tests/hardening/call_stats.h"
#include "tests/hardening/workloads.h"
#include "tests/support/server_process.h"

namespace tetrefine::hardening {
namespace {

using Clock = std::chrono::steady_clock;
using std::chrono::milliseconds;
using ::tetrefine::testing::ServerProcess;

const std::vector<RefineResult>& ExpectedResults() {
  static const auto* const expected = [] {
    auto* out = new std::vector<RefineResult>();
    for (const Workload& w : SmallWorkloads()) out->push_back(CoreResult(w));
    return out;
  }();
  return *expected;
}

// `clients` threads, each with its own connection, refine the small workloads in turn for
// `duration`; every outcome lands in `stats`.
void RunClients(const ServerProcess& server, int clients, Clock::duration duration,
                CallStats& stats) {
  const Clock::time_point end = Clock::now() + duration;
  std::vector<std::thread> threads;
  for (int c = 0; c < clients; ++c) {
    threads.emplace_back([&, c] {
      const std::shared_ptr<grpc::Channel> channel = server.NewChannel();
      for (size_t i = c; Clock::now() < end; ++i) {
        const size_t k = i % SmallWorkloads().size();
        const Workload& w = SmallWorkloads()[k];
        client::CallOptions call;
        call.deadline = std::chrono::system_clock::now() + std::chrono::seconds(30);
        const Clock::time_point start = Clock::now();
        absl::StatusOr<client::ClientResult> result =
            client::RefineViaService(channel, w.volume, w.mesh, w.options, {}, call);
        const bool correct =
            !result.ok() || ResultDifference(ExpectedResults()[k], result->result).empty();
        stats.Add(result.status(), correct, Clock::now() - start);
      }
    });
  }
  for (std::thread& t : threads) t.join();
}

void Report(const char* what, const CallStats& stats, Clock::duration duration, int clients) {
  const double seconds = std::chrono::duration<double>(duration).count();
  std::printf(
      "[load] %s: %d clients, %d calls in %.1f s = %.1f calls/s; ok %d, refused %d, other "
      "failures %d, wrong results %d; latency ok p50 %.1f ms p99 %.1f ms, refused p50 %.1f ms "
      "p99 %.1f ms\n",
      what, clients, stats.calls(), seconds, stats.calls() / seconds,
      stats.count(absl::StatusCode::kOk), stats.count(absl::StatusCode::kResourceExhausted),
      stats.calls() - stats.count(absl::StatusCode::kOk) -
          stats.count(absl::StatusCode::kResourceExhausted),
      stats.wrong(), 1e3 * stats.Quantile(absl::StatusCode::kOk, 0.5),
      1e3 * stats.Quantile(absl::StatusCode::kOk, 0.99),
      1e3 * stats.Quantile(absl::StatusCode::kResourceExhausted, 0.5),
      1e3 * stats.Quantile(absl::StatusCode::kResourceExhausted, 0.99));
  std::fflush(stdout);
}

TEST(HardeningLoadTest, ConcurrentClientsGetCorrectResultsAndMemoryStaysFlat) {
  ExpectedResults();  // computed before the clock starts
  constexpr int kClients = 8;
  constexpr int kRounds = 3;
  const Clock::duration round = milliseconds(3300);
  absl::StatusOr<std::unique_ptr<ServerProcess>> started =
      ServerProcess::Start({"--max_concurrent=8", "--threads=1"});
  ASSERT_TRUE(started.ok()) << started.status();
  std::unique_ptr<ServerProcess> server = *std::move(started);
  std::vector<int64_t> rss;
  CallStats total;
  for (int r = 1; r <= kRounds; ++r) {
    CallStats stats;
    RunClients(*server, kClients, round, stats);
    rss.push_back(server->process().RssKb());
    Report(("round " + std::to_string(r)).c_str(), stats, round, kClients);
    std::printf("[load] round %d: server VmRSS %lld kB, threads %lld\n", r,
                static_cast<long long>(rss.back()),
                static_cast<long long>(server->process().StatusField("Threads")));
    EXPECT_EQ(stats.count(absl::StatusCode::kOk), stats.calls()) << stats.ErrorSamples();
    EXPECT_EQ(stats.wrong(), 0);
    EXPECT_GE(stats.calls(), kClients);
  }
  // Round 1 warms the allocator up; a leak of even a few kB a call would show by round 3.
  if (kMemoryIsMeaningful) {
    EXPECT_LE(rss[kRounds - 1], rss[0] + std::max<int64_t>(16 * 1024, rss[0] / 10))
        << "VmRSS after round 1: " << rss[0] << " kB, after round " << kRounds << ": "
        << rss[kRounds - 1] << " kB";
  }
  EXPECT_EQ(server->Stop(), 0) << server->process().Output();
}

// With no queue (--queue_seconds=0) a call whose input is complete and finds every slot busy is
// refused at once.
TEST(HardeningLoadTest, PastTheConcurrencyLimitCallersAreRefusedQuickly) {
  ExpectedResults();
  constexpr int kClients = 8;
  const Clock::duration duration = milliseconds(4000);
  absl::StatusOr<std::unique_ptr<ServerProcess>> started =
      ServerProcess::Start({"--max_concurrent=2", "--threads=1", "--queue_seconds=0"});
  ASSERT_TRUE(started.ok()) << started.status();
  std::unique_ptr<ServerProcess> server = *std::move(started);
  CallStats warmup;
  RunClients(*server, 2, milliseconds(500), warmup);
  const int64_t rss_before = server->process().RssKb();
  const int64_t threads_before = server->process().StatusField("Threads");

  CallStats stats;
  RunClients(*server, kClients, duration, stats);
  Report("8 clients, --max_concurrent=2", stats, duration, kClients);
  const int64_t rss_after = server->process().RssKb();
  const int64_t threads_after = server->process().StatusField("Threads");
  std::printf("[load] server VmRSS %lld -> %lld kB, threads %lld -> %lld\n",
              static_cast<long long>(rss_before), static_cast<long long>(rss_after),
              static_cast<long long>(threads_before), static_cast<long long>(threads_after));

  const int ok = stats.count(absl::StatusCode::kOk);
  const int refused = stats.count(absl::StatusCode::kResourceExhausted);
  EXPECT_EQ(ok + refused, stats.calls()) << stats.ErrorSamples();
  EXPECT_GT(ok, 0);
  EXPECT_GT(refused, 0);
  EXPECT_EQ(stats.wrong(), 0);
  // A refusal costs the server nothing but the request bytes already in flight.
  EXPECT_LT(stats.Quantile(absl::StatusCode::kResourceExhausted, 0.99), 1.0);
  if (kMemoryIsMeaningful) {
    EXPECT_LT(rss_after, rss_before + 64 * 1024) << "kB";
  }
  // Thousands of refused calls leave no threads behind (the sync server's pool stays small).
  EXPECT_LT(threads_after, threads_before + 2 * kClients);
  EXPECT_EQ(server->Stop(), 0) << server->process().Output();
}

}  // namespace
}  // namespace tetrefine::hardening
