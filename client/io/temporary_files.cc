#include "client/io/temporary_files.h"

#include <signal.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstring>
#include <utility>

namespace tetrefine::io {
namespace {

// A fixed table, so that the signal handler reads it without allocating or locking: a slot is
// claimed (kWriting), its path copied, then published (kReady); the handler unlinks only
// published slots. Atomic int loads and stores, unlink, signal and raise are async-signal-safe.
constexpr int kSlots = 256;
constexpr size_t kPathBytes = 4096;
enum SlotState : int { kFree = 0, kWriting = 1, kReady = 2 };

struct Slot {
  std::atomic<int> state{kFree};
  char path[kPathBytes];
};
Slot g_slots[kSlots];

constexpr int kHandled[] = {SIGINT, SIGTERM, SIGHUP};

// Commits in progress (CommitWindow) and the signal that came during one, or 0.
std::atomic<int> g_committing{0};
std::atomic<int> g_deferred{0};

void RemoveRegistered() {
  for (Slot& slot : g_slots) {
    if (slot.state.load(std::memory_order_acquire) == kReady) ::unlink(slot.path);
  }
}

extern "C" void RemoveTemporariesAndDie(int signal_number) {
  const int saved_errno = errno;
  if (g_committing.load() > 0) {
    // Files are being renamed into place as a set: ending now would leave part of the set new
    // and part old. The commit ends the process when its renames are done.
    int none = 0;  // the first one deferred is the one the process ends by
    g_deferred.compare_exchange_strong(none, signal_number);
    RemoveTemporariesOnSignal(signal_number);  // SA_RESETHAND reset it: a third one is deferred too
    errno = saved_errno;
    return;
  }
  RemoveRegistered();
  errno = saved_errno;
  // SA_RESETHAND restored the default action; the signal is blocked while this handler runs, so
  // it is delivered, and ends the process, as the handler returns.
  ::raise(signal_number);
}

}  // namespace

CommitWindow::CommitWindow() { g_committing.fetch_add(1); }

CommitWindow::~CommitWindow() {
  if (g_committing.fetch_sub(1) != 1) return;
  if (const int signal_number = g_deferred.exchange(0); signal_number != 0) {
    RemoveRegistered();
    ::signal(signal_number, SIG_DFL);
    ::raise(signal_number);
  }
}

void RemoveTemporariesOnSignal(int signal_number) {
  struct sigaction action = {};
  action.sa_handler = RemoveTemporariesAndDie;
  action.sa_flags = SA_RESETHAND;
  sigemptyset(&action.sa_mask);
  ::sigaction(signal_number, &action, nullptr);
}

void RemoveTemporariesOnSignals() {
  for (const int signal_number : kHandled) {
    struct sigaction previous = {};
    if (::sigaction(signal_number, nullptr, &previous) != 0) continue;
    if (previous.sa_handler == SIG_IGN) continue;  // nohup, or a background job's SIGINT
    RemoveTemporariesOnSignal(signal_number);
  }
}

RegisteredTemporary::RegisteredTemporary(const std::string& path) {
  if (path.size() >= kPathBytes) return;
  for (int i = 0; i < kSlots; ++i) {
    int expected = kFree;
    if (!g_slots[i].state.compare_exchange_strong(expected, kWriting, std::memory_order_acq_rel)) {
      continue;
    }
    std::memcpy(g_slots[i].path, path.c_str(), path.size() + 1);
    g_slots[i].state.store(kReady, std::memory_order_release);
    slot_ = i;
    return;
  }
}

RegisteredTemporary::RegisteredTemporary(RegisteredTemporary&& other) noexcept
    : slot_(std::exchange(other.slot_, -1)) {}

RegisteredTemporary& RegisteredTemporary::operator=(RegisteredTemporary&& other) noexcept {
  if (this != &other) {
    if (slot_ >= 0) g_slots[slot_].state.store(kFree, std::memory_order_release);
    slot_ = std::exchange(other.slot_, -1);
  }
  return *this;
}

RegisteredTemporary::~RegisteredTemporary() {
  if (slot_ >= 0) g_slots[slot_].state.store(kFree, std::memory_order_release);
}

int RegisteredTemporaryCountForTesting() {
  int n = 0;
  for (const Slot& slot : g_slots) n += slot.state.load(std::memory_order_acquire) == kReady;
  return n;
}

}  // namespace tetrefine::io
