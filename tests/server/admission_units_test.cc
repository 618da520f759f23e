// The pieces admission is built from, one at a time: the watchdog's timers, the call gate's
// slots, memory and per-identity counts, bearer tokens, the cgroup memory limit and the worst
// case of a call.

#include <sys/resource.h>

#include <atomic>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <string>
#include <thread>
#include <vector>

#include "absl/strings/str_cat.h"
#include "gmock/gmock.h"
#include "gtest/gtest.h"
#include "server/call_gate.h"
#include "server/identity.h"
#include "server/log_rate_limit.h"
#include "server/memory_budget.h"
#include "server/watchdog.h"

namespace tetrefine::server {
namespace {

using ::testing::HasSubstr;
using Clock = std::chrono::steady_clock;
using std::chrono::milliseconds;

TEST(WatchdogTest, RunsCallbacksInTimeOrderAndNotCancelledOnes) {
  Watchdog watchdog;
  std::mutex mu;
  std::vector<int> ran;
  auto record = [&](int n) {
    return [&, n] {
      std::lock_guard<std::mutex> lock(mu);
      ran.push_back(n);
    };
  };
  const Clock::time_point now = Clock::now();
  watchdog.Schedule(now + milliseconds(60), record(3));
  const Watchdog::Id cancelled = watchdog.Schedule(now + milliseconds(40), record(99));
  watchdog.Schedule(now + milliseconds(20), record(2));
  watchdog.Schedule(now - milliseconds(5), record(1));  // already due: at once
  watchdog.Cancel(cancelled);
  for (int i = 0; i < 500; ++i) {
    {
      std::lock_guard<std::mutex> lock(mu);
      if (ran.size() == 3) break;
    }
    std::this_thread::sleep_for(milliseconds(5));
  }
  std::lock_guard<std::mutex> lock(mu);
  EXPECT_EQ(ran, (std::vector<int>{1, 2, 3}));
}

TEST(WatchdogTest, CancelWaitsForARunningCallback) {
  Watchdog watchdog;
  std::atomic<bool> started{false}, finished{false};
  const Watchdog::Id id = watchdog.Schedule(Clock::now(), [&] {
    started.store(true);
    std::this_thread::sleep_for(milliseconds(100));
    finished.store(true);
  });
  while (!started.load()) std::this_thread::sleep_for(milliseconds(1));
  watchdog.Cancel(id);
  EXPECT_TRUE(finished.load()) << "Cancel returned while the callback still ran";
}

TEST(CallGateTest, SlotsStartCallsInOrderAndFreeSlotsStartTheNext) {
  CallGate gate({.slots = 2});
  std::vector<int> started;
  std::vector<CallGate::Reservation> reservations(4);
  for (int i = 0; i < 4; ++i) {
    gate.Enqueue("a", &reservations[i], 0, [&, i] { started.push_back(i); });
  }
  EXPECT_EQ(started, (std::vector<int>{0, 1}));
  EXPECT_EQ(gate.running(), 2);
  EXPECT_EQ(gate.queued(), 2);
  gate.ReleaseSlot("a");
  EXPECT_EQ(started, (std::vector<int>{0, 1, 2}));
  gate.ReleaseSlot("a");
  gate.ReleaseSlot("a");
  EXPECT_EQ(started, (std::vector<int>{0, 1, 2, 3}));
  EXPECT_EQ(gate.running(), 1);
}

// One client's calls (four that stream every iteration and never read, each holding its slot
// for the write stall's minute) held every slot, and the other clients' calls waited their
// queue time and were refused (an outside review, 2026-11-28). An identity now holds at most
// max_slots_per_identity slots, and a freed slot goes to the waiting identity holding fewest.
TEST(CallGateTest, NoIdentityHoldsEverySlotAndAFreedSlotGoesToTheOneHoldingFewest) {
  CallGate gate({.slots = 4, .max_slots_per_identity = 3});
  std::vector<std::string> started;
  std::vector<CallGate::Reservation> reservations(8);
  int next = 0;
  const auto enqueue = [&](const std::string& who) {
    const int i = next++;
    gate.Enqueue(who, &reservations[i], 0,
                 [&, who, i] { started.push_back(absl::StrCat(who, i)); });
  };
  for (int i = 0; i < 5; ++i) enqueue("alice");
  EXPECT_EQ(started, (std::vector<std::string>{"alice0", "alice1", "alice2"}));
  EXPECT_EQ(gate.running(), 3) << "the fourth slot stays free for another client";
  enqueue("bob");  // arrives after alice's queued calls, starts at once
  EXPECT_EQ(started, (std::vector<std::string>{"alice0", "alice1", "alice2", "bob5"}));
  enqueue("bob");
  enqueue("carol");
  // A slot freed by alice: carol (none running) before bob (one) and alice (two).
  gate.ReleaseSlot("alice");
  EXPECT_EQ(started.back(), "carol7");
  // Alice and bob hold one each: the earlier call.
  gate.ReleaseSlot("alice");
  EXPECT_EQ(started.back(), "alice3");
  // Bob holds none now, alice two.
  gate.ReleaseSlot("bob");
  EXPECT_EQ(started.back(), "bob6");
  EXPECT_EQ(gate.queued(), 1);
  EXPECT_EQ(gate.running(), 4);
}

TEST(CallGateTest, AWithdrawnCallNeverStarts) {
  CallGate gate({.slots = 1});
  CallGate::Reservation first, second;
  bool second_started = false;
  gate.Enqueue("a", &first, 0, [] {});
  const uint64_t id = gate.Enqueue("a", &second, 0, [&] { second_started = true; });
  EXPECT_TRUE(gate.Withdraw(id));
  EXPECT_FALSE(gate.Withdraw(id));
  gate.ReleaseSlot("a");
  EXPECT_FALSE(second_started);
}

TEST(CallGateTest, MemoryTheWorstCaseNeedsIsReservedBeforeStartAndLaterSmallerCallsPass) {
  CallGate gate({.slots = 4, .memory_budget_bytes = 1000});
  absl::StatusOr<CallGate::Reservation> big = gate.Reserve(100, "input");
  ASSERT_TRUE(big.ok());
  CallGate::Reservation large, small;
  std::vector<std::string> started;
  gate.Enqueue("a", &*big, 700, [&] { started.push_back("big"); });
  EXPECT_EQ(gate.reserved_bytes(), 700);
  gate.Enqueue("a", &large, 600, [&] { started.push_back("large"); });  // 700 + 600 > 1000: waits
  gate.Enqueue("a", &small, 200, [&] { started.push_back("small"); });  // fits: passes it
  EXPECT_EQ(started, (std::vector<std::string>{"big", "small"}));
  EXPECT_EQ(gate.reserved_bytes(), 900);
  gate.ReleaseSlot("a");
  big->Release();  // its memory frees: the large call fits now
  EXPECT_EQ(started, (std::vector<std::string>{"big", "small", "large"}));
  EXPECT_EQ(large.bytes(), 600);
  EXPECT_FALSE(gate.FitsEver(1001));
  EXPECT_TRUE(gate.FitsEver(1000));
}

// A finished call keeps only what its result needs while it is written: the rest of its worst
// case goes back to the budget and starts the calls waiting for it (an outside review,
// 2026-11-28: a default call that was not read kept 90% of the budget for a minute).
TEST(CallGateTest, AShrunkReservationStartsTheCallsThatFitNow) {
  CallGate gate({.slots = 4, .memory_budget_bytes = 1000});
  CallGate::Reservation finished = *gate.Reserve(0, "finished");
  CallGate::Reservation waiting = *gate.Reserve(0, "waiting");
  std::vector<std::string> started;
  gate.Enqueue("a", &finished, 900, [&] { started.push_back("finished"); });
  gate.Enqueue("b", &waiting, 500, [&] { started.push_back("waiting"); });
  EXPECT_EQ(started, (std::vector<std::string>{"finished"}));
  gate.ReleaseSlot("a");
  finished.ShrinkTo(2000);  // never grows
  EXPECT_EQ(finished.bytes(), 900);
  finished.ShrinkTo(300);
  EXPECT_EQ(finished.bytes(), 300);
  EXPECT_EQ(started, (std::vector<std::string>{"finished", "waiting"}));
  EXPECT_EQ(gate.reserved_bytes(), 800);
  finished.Release();
  EXPECT_EQ(gate.reserved_bytes(), 500);
}

// Sixteen slow uploads of one client held the whole memory budget, and every other client's
// call was refused for memory (an outside review, 2026-11-28). One client's uploads now hold at
// most max_input_bytes_per_identity together, unless one upload is all it has.
TEST(CallGateTest, OneClientsUploadsHoldAtMostTheirShare) {
  CallGate gate({.slots = 4, .max_input_bytes_per_identity = 500, .memory_budget_bytes = 1000});
  absl::StatusOr<CallGate::Reservation> first = gate.Reserve(300, "alice's first", "alice");
  ASSERT_TRUE(first.ok());
  const absl::StatusOr<CallGate::Reservation> second = gate.Reserve(300, "alice's second", "alice");
  ASSERT_EQ(second.status().code(), absl::StatusCode::kResourceExhausted);
  EXPECT_THAT(second.status().message(),
              HasSubstr("client alice's other uploads hold 300 B of the 500 B one client's "
                        "uploads may hold"));
  absl::StatusOr<CallGate::Reservation> bobs = gate.Reserve(300, "bob's", "bob");
  ASSERT_TRUE(bobs.ok()) << "another client is not affected";
  bobs->Release();
  // Alone, one upload may grow past the share (a large volume), within the budget.
  EXPECT_TRUE(first->GrowTo(800, "alice's first").ok());
  EXPECT_EQ(gate.Reserve(100, "alice's second", "alice").status().code(),
            absl::StatusCode::kResourceExhausted);
  // Admitted to refine, it is no upload any more: alice may upload again.
  bool started = false;
  gate.Enqueue("alice", &*first, 800, [&] { started = true; });
  ASSERT_TRUE(started);
  absl::StatusOr<CallGate::Reservation> again = gate.Reserve(100, "alice's next", "alice");
  EXPECT_TRUE(again.ok()) << again.status();
}

// A client that started a call every 5 s and never read the results held the whole budget with
// finished calls, and every other client was refused (an outside review, 2026-11-29). All of one
// client's calls, in any phase, hold at most max_bytes_per_identity together, unless one call is
// all it has: at arrival a call over it is refused, and a queued one waits.
TEST(CallGateTest, OneClientsCallsHoldAtMostTheirShareInEveryPhase) {
  CallGate gate({.slots = 4, .max_bytes_per_identity = 600, .memory_budget_bytes = 1000});
  // Alice's first call refines and finishes; its result waits for a reader that never comes.
  absl::StatusOr<CallGate::Reservation> result = gate.Reserve(100, "alice's first", "alice");
  ASSERT_TRUE(result.ok());
  bool started = false;
  gate.Enqueue("alice", &*result, 700, [&] { started = true; });  // alone: past the share
  ASSERT_TRUE(started);
  gate.ReleaseSlot("alice");
  result->ShrinkTo(500);
  EXPECT_EQ(gate.held_bytes("alice"), 500);
  // Her next call opens (500 + 50 <= 600) but may not start refining at its worst case.
  absl::StatusOr<CallGate::Reservation> next = gate.Reserve(50, "alice's next", "alice");
  ASSERT_TRUE(next.ok()) << next.status();
  bool next_started = false;
  const uint64_t waiting = gate.Enqueue("alice", &*next, 300, [&] { next_started = true; });
  EXPECT_FALSE(next_started);
  // A third may not even open: the arrival is refused by name.
  const absl::StatusOr<CallGate::Reservation> third = gate.Reserve(100, "a new call", "alice");
  ASSERT_EQ(third.status().code(), absl::StatusCode::kResourceExhausted);
  EXPECT_THAT(third.status().message(),
              HasSubstr("client alice's other calls hold 550 B of the 600 B one client's calls "
                        "may hold together"));
  // Bob's call fits beside hers and starts at once.
  absl::StatusOr<CallGate::Reservation> bobs = gate.Reserve(50, "bob's", "bob");
  ASSERT_TRUE(bobs.ok()) << bobs.status();
  bool bob_started = false;
  gate.Enqueue("bob", &*bobs, 300, [&] { bob_started = true; });
  EXPECT_TRUE(bob_started);
  EXPECT_FALSE(next_started);
  // Once alice's result is read (released), her waiting call starts.
  result->Release();
  EXPECT_TRUE(next_started);
  EXPECT_FALSE(gate.Withdraw(waiting));
  EXPECT_EQ(gate.held_bytes("alice"), 300);
}

TEST(CallGateTest, AReservationThatDoesNotFitSaysHowMuchIsFree) {
  CallGate gate({.slots = 1, .memory_budget_bytes = 4 << 20});
  absl::StatusOr<CallGate::Reservation> a = gate.Reserve(3 << 20, "call a");
  ASSERT_TRUE(a.ok());
  absl::StatusOr<CallGate::Reservation> b = gate.Reserve(2 << 20, "call b");
  ASSERT_FALSE(b.ok());
  EXPECT_EQ(b.status().code(), absl::StatusCode::kResourceExhausted);
  EXPECT_THAT(b.status().message(), HasSubstr("call b needs 2.0 MiB"));
  EXPECT_THAT(b.status().message(), HasSubstr("1.0 MiB of 4.0 MiB are free"));
  EXPECT_THAT(b.status().message(), HasSubstr("retry"));
  a->Release();
  EXPECT_TRUE(gate.Reserve(2 << 20, "call b").ok());
}

TEST(CallGateTest, OpenCallsAreCountedPerIdentity) {
  CallGate gate({.slots = 1, .max_calls_per_identity = 2});
  absl::StatusOr<CallGate::Ticket> a1 = gate.Open("peer:a");
  absl::StatusOr<CallGate::Ticket> a2 = gate.Open("peer:a");
  ASSERT_TRUE(a1.ok() && a2.ok());
  absl::StatusOr<CallGate::Ticket> a3 = gate.Open("peer:a");
  EXPECT_EQ(a3.status().code(), absl::StatusCode::kResourceExhausted);
  EXPECT_THAT(a3.status().message(), HasSubstr("client peer:a already has 2 Refine calls open"));
  EXPECT_THAT(a3.status().message(), HasSubstr("--max_calls_per_identity"));
  EXPECT_TRUE(gate.Open("peer:b").ok()) << "another identity is not affected";
  a1->Release();
  EXPECT_TRUE(gate.Open("peer:a").ok());
  EXPECT_EQ(gate.open_calls(), 1);  // a2; the temporaries are released at once
  gate.StopAdmitting();
  EXPECT_EQ(gate.Open("peer:c").status().code(), absl::StatusCode::kUnavailable);
}

// A call whose final status is on its way no longer counts against its client's limit, but is
// still open until released (a draining server waits for it).
TEST(CallGateTest, AFinishingCallFreesItsIdentitysPlaceButStaysOpen) {
  CallGate gate({.slots = 1, .max_calls_per_identity = 1});
  absl::StatusOr<CallGate::Ticket> a1 = gate.Open("peer:a");
  ASSERT_TRUE(a1.ok());
  EXPECT_EQ(gate.Open("peer:a").status().code(), absl::StatusCode::kResourceExhausted);
  a1->EndForIdentity();
  a1->EndForIdentity();  // once only
  EXPECT_EQ(gate.open_calls(), 1);
  absl::StatusOr<CallGate::Ticket> a2 = gate.Open("peer:a");
  ASSERT_TRUE(a2.ok()) << a2.status();
  EXPECT_EQ(gate.open_calls(), 2);
  // Moved, released: a1 no longer counts for peer:a, and releasing it leaves a2's count alone.
  CallGate::Ticket moved = *std::move(a1);
  moved.Release();
  EXPECT_EQ(gate.open_calls(), 1);
  EXPECT_EQ(gate.Open("peer:a").status().code(), absl::StatusCode::kResourceExhausted);
  a2->Release();
  EXPECT_EQ(gate.open_calls(), 0);
  EXPECT_TRUE(gate.Open("peer:a").ok());
}

TEST(TokenTableTest, FindsTheIdentityOfEachTokenAndNothingElse) {
  absl::StatusOr<TokenTable> table = TokenTable::FromText(
      "# operators\n"
      "alice  0123456789abcdef0123\n"
      "\n"
      "bob\tsecret-token-of-bob-42\n"
      "alice  rotated-token-of-alice-77\n",
      "tokens.txt");
  ASSERT_TRUE(table.ok()) << table.status();
  EXPECT_EQ(table->size(), 3u);
  EXPECT_EQ(table->Find("0123456789abcdef0123"), "alice");
  EXPECT_EQ(table->Find("rotated-token-of-alice-77"), "alice");
  EXPECT_EQ(table->Find("secret-token-of-bob-42"), "bob");
  EXPECT_EQ(table->Find("secret-token-of-bob-4"), std::nullopt);
  EXPECT_EQ(table->Find("secret-token-of-bob-421"), std::nullopt);
  EXPECT_EQ(table->Find(""), std::nullopt);
}

TEST(TokenTableTest, BadLinesAreNamedWithTheirLineNumber) {
  struct Case {
    std::string text;
    std::string message;
  };
  for (const Case& c : std::vector<Case>{
           {"alice\n", "t:1: expected \"<identity> <token>\""},
           {"ok 0123456789abcdef\nbad! 0123456789abcdefgh\n", "t:2: identity 'bad!'"},
           {"alice short\n", "t:1: the token of alice has 5 characters; at least 16"},
           {"a 0123456789abcdef\nb 0123456789abcdef\n",
            "t:2: the token of b is already the token of a"},
           {"# nothing\n\n", "t: no tokens"},
       }) {
    absl::StatusOr<TokenTable> table = TokenTable::FromText(c.text, "t");
    ASSERT_FALSE(table.ok()) << c.text;
    EXPECT_EQ(table.status().code(), absl::StatusCode::kInvalidArgument);
    EXPECT_THAT(table.status().message(), HasSubstr(c.message));
  }
  EXPECT_EQ(TokenTable::FromFile("/nonexistent/tokens").status().code(),
            absl::StatusCode::kNotFound);
}

TEST(PeerAddressTest, DropsThePort) {
  EXPECT_EQ(PeerAddress("ipv4:10.0.0.7:51234"), "10.0.0.7");
  EXPECT_EQ(PeerAddress("ipv6:[::1]:5000"), "[::1]");
  // IPv6 clients count by their /64 (a host holds 2^64 addresses: a service sweep); mapped IPv4
  // addresses by their IPv4 one.
  EXPECT_EQ(PeerAddress("ipv6:[2001:db8:1:2:aaaa:bbbb:cccc:dddd]:443"), "[2001:db8:1:2::]/64");
  EXPECT_EQ(PeerAddress("ipv6:[2001:db8:1:2::7]:5000"), PeerAddress("ipv6:[2001:db8:1:2::8]:5001"));
  EXPECT_NE(PeerAddress("ipv6:[2001:db8:1:2::7]:5000"), PeerAddress("ipv6:[2001:db8:1:3::7]:5000"));
  EXPECT_EQ(PeerAddress("ipv6:[fe80::1%eth0]:5000"), "[fe80::]/64");
  EXPECT_EQ(PeerAddress("ipv6:[::ffff:10.0.0.7]:5000"), "10.0.0.7");
  EXPECT_EQ(PeerAddress("ipv6:[not an address]:5000"), "[not an address]");
  EXPECT_EQ(PeerAddress("unix:/tmp/socket"), "unix:/tmp/socket");
  EXPECT_EQ(PeerAddress("inproc"), "inproc");
}

class CgroupTest : public ::testing::Test {
 protected:
  void SetUp() override {
    root_ = std::filesystem::temp_directory_path() /
            ("tetrefine_cgroup_" + std::to_string(::getpid()) + "_" +
             ::testing::UnitTest::GetInstance()->current_test_info()->name());
    std::filesystem::remove_all(root_);
    std::filesystem::create_directories(root_ / "proc/self");
  }
  void TearDown() override { std::filesystem::remove_all(root_); }
  void Write(const std::string& relative, const std::string& text) {
    const std::filesystem::path path = root_ / relative;
    std::filesystem::create_directories(path.parent_path());
    std::ofstream(path) << text;
  }
  std::filesystem::path root_;
};

TEST_F(CgroupTest, V2LimitAtTheRootOrOnTheOwnPath) {
  Write("proc/self/cgroup", "0::/\n");
  Write("sys/fs/cgroup/memory.max", "8589934592\n");
  EXPECT_EQ(CgroupMemoryLimit(root_.string()), int64_t{8} << 30);
  Write("proc/self/cgroup", "0::/kubepods/pod1\n");
  Write("sys/fs/cgroup/memory.max", "max\n");
  Write("sys/fs/cgroup/kubepods/pod1/memory.max", "1073741824\n");
  EXPECT_EQ(CgroupMemoryLimit(root_.string()), int64_t{1} << 30);
}

TEST_F(CgroupTest, V1LimitAndItsUnlimitedValue) {
  Write("proc/self/cgroup", "4:memory:/docker/abc\n0::/\n");
  Write("sys/fs/cgroup/memory/memory.limit_in_bytes", "9223372036854771712\n");
  EXPECT_EQ(CgroupMemoryLimit(root_.string()), std::nullopt);
  Write("sys/fs/cgroup/memory/docker/abc/memory.limit_in_bytes", "536870912\n");
  EXPECT_EQ(CgroupMemoryLimit(root_.string()), int64_t{512} << 20);
}

TEST_F(CgroupTest, NoCgroupFilesNoLimit) {
  EXPECT_EQ(CgroupMemoryLimit(root_.string()), std::nullopt);
  EXPECT_GT(PhysicalMemoryBytes(), int64_t{64} << 20);
}

// A flood of refused calls wrote 47 MB of access log in 15 s (an outside review, 2026-11-29): at
// most `per_second` lines a second, and the next line says how many were left out.
TEST(LogRateLimitTest, AtMostSoManyLinesASecondAndTheRestCounted) {
  LogRateLimit limit(3);
  const LogRateLimit::Clock::time_point t0 = LogRateLimit::Clock::now();
  int64_t suppressed = -1;
  for (int i = 0; i < 3; ++i) {
    EXPECT_TRUE(limit.Allow(&suppressed, t0 + std::chrono::milliseconds(100 * i)));
    EXPECT_EQ(suppressed, 0);
  }
  for (int i = 0; i < 5; ++i) {
    EXPECT_FALSE(limit.Allow(&suppressed, t0 + std::chrono::milliseconds(500 + 10 * i)));
  }
  // A second later the window has room again, and the first line says five were not logged.
  EXPECT_TRUE(limit.Allow(&suppressed, t0 + std::chrono::milliseconds(1000)));
  EXPECT_EQ(suppressed, 5);
  EXPECT_TRUE(limit.Allow(&suppressed, t0 + std::chrono::milliseconds(1001)));
  EXPECT_EQ(suppressed, 0);
}

// The soft RLIMIT_AS of this process, set for the test's scope and put back after it.
class AddressSpaceLimit {
 public:
  explicit AddressSpaceLimit(rlim_t soft) {
    getrlimit(RLIMIT_AS, &saved_);
    rlimit limited = saved_;
    limited.rlim_cur = soft;
    ok_ = setrlimit(RLIMIT_AS, &limited) == 0;
  }
  ~AddressSpaceLimit() { setrlimit(RLIMIT_AS, &saved_); }
  bool ok() const { return ok_; }

 private:
  rlimit saved_{};
  bool ok_ = false;
};

TEST(AddressSpaceLeftTest, WhatUlimitLeavesOfTheAddressSpace) {
#if defined(__SANITIZE_ADDRESS__)
  GTEST_SKIP() << "AddressSanitizer maps terabytes of shadow memory: no address-space limit fits";
#else
  rlimit now{};
  ASSERT_EQ(getrlimit(RLIMIT_AS, &now), 0);
  rlimit data{};
  ASSERT_EQ(getrlimit(RLIMIT_DATA, &data), 0);
  if (now.rlim_cur == RLIM_INFINITY && data.rlim_cur == RLIM_INFINITY) {
    EXPECT_EQ(AddressSpaceLeft(), std::nullopt);
  }
  // 512 MiB above what is mapped now (measured from /proc, as the function measures it).
  int64_t mapped_kb = 0;
  std::ifstream status("/proc/self/status");
  for (std::string line; std::getline(status, line);) {
    if (line.rfind("VmSize:", 0) == 0) mapped_kb = std::stoll(line.substr(7));
  }
  ASSERT_GT(mapped_kb, 0);
  const int64_t extra = int64_t{512} << 20;
  std::optional<int64_t> left;
  {
    AddressSpaceLimit limit(static_cast<rlim_t>(mapped_kb * 1024 + extra));
    ASSERT_TRUE(limit.ok());
    left = AddressSpaceLeft();
  }
  ASSERT_TRUE(left.has_value());
  EXPECT_LE(*left, extra);
  EXPECT_GT(*left, extra - (int64_t{64} << 20));  // less what the reading itself mapped
  {
    AddressSpaceLimit limit(static_cast<rlim_t>(mapped_kb * 1024 / 2));  // already exceeded
    ASSERT_TRUE(limit.ok());
    left = AddressSpaceLeft();
  }
  EXPECT_EQ(left, int64_t{0});
#endif
}

TEST(MemoryBudgetTest, BudgetLeavesTheProcessItsShare) {
  EXPECT_EQ(BudgetForLimit(int64_t{8} << 30), (int64_t{8} << 30) - (int64_t{8} << 30) / 10);
  EXPECT_EQ(BudgetForLimit(int64_t{1} << 30), (int64_t{1} << 30) - (int64_t{256} << 20));
  EXPECT_EQ(BudgetForLimit(int64_t{100} << 20), 0);
}

TEST(MemoryBudgetTest, WorstCaseOutputIsTheBudgetOrWhatTheIterationsCanReach) {
  // The subdivision table: configuration 6 makes 8 children, a prism with a Steiner point more.
  EXPECT_GE(MaxChildrenPerTet(), 8);
  EXPECT_LE(MaxChildrenPerTet(), 11);
  const int64_t g = MaxChildrenPerTet();
  EXPECT_EQ(WorstCaseOutputTets(40, 0, 1'000'000), 40);
  EXPECT_EQ(WorstCaseOutputTets(40, 2, 1'000'000), 40 * g * g);
  EXPECT_EQ(WorstCaseOutputTets(40, 16, 1'000'000), 1'000'000);
  EXPECT_EQ(WorstCaseOutputTets(40, 1'000'000'000, 50'000'000), 50'000'000);
  EXPECT_EQ(HumanBytes(1536), "1.5 KiB");
  EXPECT_EQ(HumanBytes(12), "12 B");
}

}  // namespace
}  // namespace tetrefine::server
