// Good clients among hostile and greedy ones, against one tetrefine_server process on loopback
// with a 2 GiB memory limit: clients that open streams and send nothing, that read their result
// slowly or not at all, that ask for a tiny epsilon (refinement up to the tet budget), and that
// ask for heavy lattice checks. Every loop is bounded in count and in time. What must hold: no
// wrong result, every good client served (retrying when told to), the server's peak memory
// under its budget, and a clean exit. The figures it prints are in docs/results/service_abuse.md.
//
// Also: the server's peak memory per output tet for single large calls, which must stay under
// the bytes per output tet the server reserves by default (--bytes_per_output_tet).

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "client/refine_client.h"
#include "gtest/gtest.h"
#include "server/memory_budget.h"
#include "tests/hardening/call_stats.h"
#include "tests/hardening/workloads.h"
#include "tests/support/child_process.h"
#include "tests/support/server_process.h"
#include "tetrefine/v1/tetrefine.grpc.pb.h"
#include "wire/request_writer.h"

namespace tetrefine::hardening {
namespace {

using ::tetrefine::testing::ChildProcess;
using ::tetrefine::testing::ServerProcess;
using Clock = std::chrono::steady_clock;
using std::chrono::milliseconds;
using Stream = grpc::ClientReaderWriter<v1::RefineRequest, v1::RefineResponse>;

constexpr int64_t kMemoryLimit = int64_t{2} << 30;
constexpr int64_t kMaxOutputTets = 2'000'000;

// Counts of outcomes by label ("good OK", "idle DEADLINE_EXCEEDED", ...).
class Tally {
 public:
  void Add(const std::string& who, absl::StatusCode code) {
    std::lock_guard<std::mutex> lock(mu_);
    ++counts_[who + " " + absl::StatusCodeToString(code)];
  }
  std::string Report() const {
    std::lock_guard<std::mutex> lock(mu_);
    std::string out;
    for (const auto& [what, n] : counts_) out += "  " + what + ": " + std::to_string(n) + "\n";
    return out;
  }

 private:
  mutable std::mutex mu_;
  std::map<std::string, int> counts_;
};

// Samples the server's resident memory until stopped; the largest sample, kB.
class RssWatcher {
 public:
  explicit RssWatcher(const ChildProcess& process)
      : thread_([this, &process] {
          while (!stop_.load()) {
            peak_kb_.store(std::max(peak_kb_.load(), process.RssKb()));
            std::this_thread::sleep_for(milliseconds(20));
          }
        }) {}
  ~RssWatcher() { Stop(); }
  int64_t Stop() {
    stop_.store(true);
    if (thread_.joinable()) thread_.join();
    return peak_kb_.load();
  }

 private:
  std::atomic<bool> stop_{false};
  std::atomic<int64_t> peak_kb_{0};
  std::thread thread_;
};

std::string WriteTokenFile() {
  const std::string path = (std::filesystem::temp_directory_path() /
                            ("tetrefine_abuse_tokens_" + std::to_string(::getpid())))
                               .string();
  std::ofstream(path) << "good good-token-0123456789abcdef\n"
                         "idle idle-token-0123456789abcdef\n"
                         "slow slow-token-0123456789abcdef\n"
                         "greedy greedy-token-0123456789abcdef\n"
                         "lattice lattice-token-0123456789abcdef\n";
  return path;
}

std::string Token(const std::string& identity) { return identity + "-token-0123456789abcdef"; }

// BigResultWorkload in 256 KB response messages, without a declared tet budget.
Workload BigResultInSmallMessages() {
  Workload w = BigResultWorkload();
  w.options.send_max_tets = false;
  w.options.response_chunk_bytes = 256 << 10;
  return w;
}

TEST(HardeningAbuseLoadTest, GoodClientsAreServedCorrectlyAmongHostileOnesWithinTheMemoryBudget) {
  const std::vector<RefineResult> expected_small = [] {
    std::vector<RefineResult> out;
    for (const Workload& w : SmallWorkloads()) out.push_back(CoreResult(w));
    return out;
  }();
  wire::ServiceLimits limits;
  limits.max_output_tets = kMaxOutputTets;
  const RefineResult expected_greedy = CoreResult(TinyEpsilon(), limits);
  const std::string tokens = WriteTokenFile();
  absl::StatusOr<std::unique_ptr<ServerProcess>> started = ServerProcess::Start(
      {"--threads=1", "--max_concurrent=2", "--memory_limit_bytes=" + std::to_string(kMemoryLimit),
       "--max_output_tets=" + std::to_string(kMaxOutputTets), "--input_deadline_seconds=6",
       "--idle_timeout_seconds=2", "--write_stall_seconds=2", "--queue_seconds=3",
       "--max_call_seconds=20", "--max_calls_per_identity=6", "--token_file=" + tokens,
       "--drain_seconds=5"});
  ASSERT_TRUE(started.ok()) << started.status();
  std::unique_ptr<ServerProcess> server = *std::move(started);
  const int64_t budget = server::BudgetForLimit(kMemoryLimit);
  const int64_t rss_idle_kb = server->process().RssKb();
  RssWatcher rss(server->process());

  const Clock::time_point end = Clock::now() + std::chrono::seconds(20);
  auto running = [&] { return Clock::now() < end; };
  Tally tally;
  CallStats good_stats;
  std::atomic<int> good_served{0}, good_unserved{0}, good_retries{0}, wrong{0};
  std::vector<std::thread> threads;

  // Good clients: small refinements, each retried (at most 20 times, after the server's
  // suggested delay) until it is served; each result checked bit for bit.
  for (int c = 0; c < 4; ++c) {
    threads.emplace_back([&, c] {
      const std::shared_ptr<grpc::Channel> channel = server->NewChannel();
      for (size_t i = c; running() && i < static_cast<size_t>(c) + 200; ++i) {
        const size_t k = i % SmallWorkloads().size();
        const Workload& w = SmallWorkloads()[k];
        client::CallOptions call;
        call.bearer_token = Token("good");
        const Clock::time_point start = Clock::now();
        absl::StatusOr<client::ClientResult> result;
        for (int attempt = 0; attempt < 20; ++attempt) {
          call.deadline = std::chrono::system_clock::now() + std::chrono::seconds(30);
          result = client::RefineViaService(channel, w.volume, w.mesh, w.options, {}, call);
          tally.Add("good", result.status().code());
          if (!absl::IsResourceExhausted(result.status())) break;
          ++good_retries;
          std::this_thread::sleep_for(milliseconds(200));
        }
        const bool correct =
            !result.ok() || ResultDifference(expected_small[k], result->result).empty();
        good_stats.Add(result.status(), correct, Clock::now() - start);
        if (!correct) ++wrong;
        (result.ok() ? good_served : good_unserved)++;
      }
    });
  }
  // Idle: streams that open and send nothing, eight at a time (more than the quota of six).
  threads.emplace_back([&] {
    const std::shared_ptr<grpc::Channel> channel = server->NewChannel();
    for (int round = 0; running() && round < 20; ++round) {
      std::vector<std::unique_ptr<grpc::ClientContext>> contexts;
      std::vector<std::unique_ptr<Stream>> streams;
      v1::Refiner::Stub stub(channel);
      for (int i = 0; i < 8; ++i) {
        contexts.push_back(std::make_unique<grpc::ClientContext>());
        contexts.back()->AddMetadata("authorization", "Bearer " + Token("idle"));
        contexts.back()->set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(30));
        streams.push_back(stub.Refine(contexts.back().get()));
      }
      for (auto& stream : streams) {
        for (v1::RefineResponse response; stream->Read(&response);) {
        }
        tally.Add("idle", static_cast<absl::StatusCode>(stream->Finish().error_code()));
      }
    }
  });
  // Slow and stopped readers of large results: one takes a message every 100 ms (under the
  // stall bound, so its call runs into --max_call_seconds or ends), one reads nothing.
  for (int c = 0; c < 2; ++c) {
    threads.emplace_back([&, c] {
      const Workload w = BigResultInSmallMessages();
      std::vector<v1::RefineRequest> requests;
      wire::WriteRequest(w.options, w.volume, w.mesh, size_t{1} << 20,
                         [&](const v1::RefineRequest& r) {
                           requests.push_back(r);
                           return true;
                         });
      const std::shared_ptr<grpc::Channel> channel = server->NewChannel();
      for (int round = 0; running() && round < 5; ++round) {
        v1::Refiner::Stub stub(channel);
        grpc::ClientContext context;
        context.AddMetadata("authorization", "Bearer " + Token("slow"));
        context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(60));
        auto stream = stub.Refine(&context);
        for (const v1::RefineRequest& r : requests) {
          if (!stream->Write(r)) break;
        }
        stream->WritesDone();
        if (c == 1) std::this_thread::sleep_for(std::chrono::seconds(4));  // never reads
        for (v1::RefineResponse response; stream->Read(&response);) {
          if (c == 0) std::this_thread::sleep_for(milliseconds(100));
        }
        tally.Add(c == 0 ? "slow-reader" : "stopped-reader",
                  static_cast<absl::StatusCode>(stream->Finish().error_code()));
      }
    });
  }
  // Greedy: a tiny epsilon (refined up to the 2M-tet budget, result checked), and asks beyond
  // the server's limits (refused with the options).
  threads.emplace_back([&] {
    const std::shared_ptr<grpc::Channel> channel = server->NewChannel();
    for (int round = 0; running() && round < 6; ++round) {
      Workload w = TinyEpsilon();
      client::CallOptions call;
      call.bearer_token = Token("greedy");
      call.deadline = std::chrono::system_clock::now() + std::chrono::seconds(60);
      if (round % 2 == 1) w.options.SetMaxTets(50'000'000);  // above --max_output_tets
      absl::StatusOr<client::ClientResult> result =
          client::RefineViaService(channel, w.volume, w.mesh, w.options, {}, call);
      tally.Add(round % 2 == 1 ? "greedy-over-limit" : "greedy", result.status().code());
      if (result.ok()) {
        if (result->result.stop_reason != expected_greedy.stop_reason ||
            result->result.iterations.size() != expected_greedy.iterations.size() ||
            result->result.iterations.back().final_tets !=
                expected_greedy.iterations.back().final_tets) {
          ++wrong;
        }
      }
    }
  });
  // Lattice-heavy: order 64, every tet at order 16, and the heaviest check the caps allow.
  threads.emplace_back([&] {
    const std::shared_ptr<grpc::Channel> channel = server->NewChannel();
    for (int round = 0; running() && round < 9; ++round) {
      Workload w = SmallWorkloads()[round % 2];
      if (round % 3 == 0) {
        w.options.refine.lattice_n = 64;
      } else if (round % 3 == 1) {
        w.options.refine.lattice_n = 16;
        w.options.refine.lattice_max_tets = 0;
      } else {
        w.options.refine.lattice_n = 16;
        w.options.refine.lattice_max_tets = 200'000;  // 1.9e8 points at most: within the cap
      }
      client::CallOptions call;
      call.bearer_token = Token("lattice");
      call.deadline = std::chrono::system_clock::now() + std::chrono::seconds(60);
      absl::StatusOr<client::ClientResult> result =
          client::RefineViaService(channel, w.volume, w.mesh, w.options, {}, call);
      tally.Add("lattice-n" + std::to_string(w.options.refine.lattice_n) +
                    (w.options.refine.lattice_max_tets == 0 ? "-every-tet" : ""),
                result.status().code());
    }
  });
  for (std::thread& t : threads) t.join();
  const int64_t peak_kb = rss.Stop();
  const int64_t hwm_kb = server->process().StatusField("VmHWM");

  std::printf("[abuse-load] outcomes:\n%s", tally.Report().c_str());
  std::printf(
      "[abuse-load] good calls: %d served, %d not served, %d retries after RESOURCE_EXHAUSTED, "
      "%d wrong results; latency p50 %.1f ms, p99 %.1f ms (including retries)\n",
      good_served.load(), good_unserved.load(), good_retries.load(), wrong.load(),
      1e3 * good_stats.Quantile(absl::StatusCode::kOk, 0.5),
      1e3 * good_stats.Quantile(absl::StatusCode::kOk, 0.99));
  std::printf(
      "[abuse-load] server memory: idle %.1f MiB, peak sampled %.1f MiB, VmHWM %.1f MiB; budget "
      "%.1f MiB (limit %.1f MiB)\n",
      rss_idle_kb / 1024.0, peak_kb / 1024.0, hwm_kb / 1024.0, budget / 1048576.0,
      kMemoryLimit / 1048576.0);
  std::fflush(stdout);

  EXPECT_EQ(wrong.load(), 0);
  EXPECT_GT(good_served.load(), 0);
  EXPECT_EQ(good_unserved.load(), 0) << good_stats.ErrorSamples();
  if (kMemoryIsMeaningful) {
    EXPECT_LT(hwm_kb * 1024, budget);
  }
  EXPECT_EQ(server->Stop(), 0) << server->process().Output();
  std::filesystem::remove(tokens);
}

// The server's peak memory for one call, per output tet: what --bytes_per_output_tet assumes.
TEST(HardeningAbuseLoadTest, PeakMemoryPerOutputTetIsWithinTheReservedRate) {
  if (!kMemoryIsMeaningful) GTEST_SKIP() << "AddressSanitizer inflates resident memory";
  struct Case {
    std::string name;
    Workload w;
  };
  std::vector<Case> cases;
  cases.push_back({"135k -> 1.08M tets, result sent", BigResultInSmallMessages()});
  Workload two = BigResultInSmallMessages();
  two.options.refine.max_iterations = 2;
  two.options.skip_final_mesh = true;
  cases.push_back({"135k -> 8.6M tets, statistics only", two});
  for (const Case& c : cases) {
    absl::StatusOr<std::unique_ptr<ServerProcess>> started =
        ServerProcess::Start({"--threads=2", "--drain_seconds=2"});
    ASSERT_TRUE(started.ok()) << started.status();
    std::unique_ptr<ServerProcess> server = *std::move(started);
    const int64_t idle_kb = server->process().StatusField("VmHWM");
    client::CallOptions call;
    call.deadline = std::chrono::system_clock::now() + std::chrono::seconds(120);
    absl::StatusOr<client::ClientResult> result =
        client::RefineViaService(server->NewChannel(), c.w.volume, c.w.mesh, c.w.options, {}, call);
    ASSERT_TRUE(result.ok()) << result.status();
    const int64_t tets = result->result.iterations.back().final_tets;
    const int64_t peak_kb = server->process().StatusField("VmHWM");
    const double per_tet =
        static_cast<double>(peak_kb - idle_kb) * 1024.0 / static_cast<double>(tets);
    std::printf("[abuse-load] %s: server peak %.1f MiB above idle, %.1f bytes per output tet\n",
                c.name.c_str(), (peak_kb - idle_kb) / 1024.0, per_tet);
    std::fflush(stdout);
    EXPECT_LT(per_tet, static_cast<double>(server::kDefaultBytesPerOutputTet));
    EXPECT_EQ(server->Stop(), 0);
  }
}

}  // namespace
}  // namespace tetrefine::hardening
