#pragma once

// Admission of Refine calls: what a call may hold, and when it may start refining.
//
// A call holds three kinds of resource, each taken when it is needed and bounded separately, so
// that no kind of client can hold the others hostage:
//   - an open-call ticket from its arrival (one of max_calls_per_identity for its identity);
//   - memory, reserved as the headers declare it (the input) and at admission (the output at its
//     tet budget), against memory_budget_bytes;
//   - a refinement slot (one of max_concurrent_refinements) only from the moment its input is
//     complete until its refinement's CPU work ends; a finished result waiting for a slow
//     reader holds memory (its own size's, no longer its worst case's), not a slot. One identity
//     holds at most max_slots_per_identity slots at once, and a freed slot goes to the waiting
//     identity that holds the fewest: a client with four calls that stream every iteration and
//     never read held all four slots of a server for a minute each, and every other client's call
//     was refused (an outside review, 2026-11-28).
// What one identity's calls hold together (uploads, refinements at their worst case, results
// waiting for their reader) is capped too, unless it is one call's alone: a client that started
// a call every 5 s and never read the results held the whole budget with finished calls until
// the write stall ended each a minute later, and every other client's call was refused (an outside
// review, 2026-11-29). The server sets the cap so that another client's call with default
// options still fits beside it.

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <list>
#include <map>
#include <mutex>
#include <string>

#include "absl/status/status.h"
#include "absl/status/statusor.h"

namespace tetrefine::server {

class CallGate {
 public:
  struct Config {
    int slots = 4;                   // refinements at once, >= 1
    int max_calls_per_identity = 0;  // open calls of one identity; 0: no limit
    int max_slots_per_identity = 0;  // slots one identity holds at once; 0: no limit
    // Memory one identity's calls may hold while they upload (before they are admitted to
    // refine), unless it is one call's alone; 0: no limit. Many slow uploads of one client filled
    // the budget and every other client was refused for memory (an outside review, 2026-11-28).
    int64_t max_input_bytes_per_identity = 0;
    // Memory all of one identity's calls may hold together, in any phase, unless it is one
    // call's alone; 0: no limit.
    int64_t max_bytes_per_identity = 0;
    int64_t memory_budget_bytes = 0;  // 0: memory is not budgeted
  };
  explicit CallGate(const Config& config) : config_(config) {}
  CallGate(const CallGate&) = delete;
  CallGate& operator=(const CallGate&) = delete;

  // Memory held by one call; released when destroyed.
  class Reservation {
   public:
    Reservation() = default;
    ~Reservation() { Release(); }
    Reservation(Reservation&& other) noexcept;
    Reservation& operator=(Reservation&& other) noexcept;
    // Grows the reservation to `total` bytes (nothing if it already holds as much).
    // RESOURCE_EXHAUSTED, saying how much is needed, held and free, when that does not fit now;
    // the reservation is then unchanged.
    absl::Status GrowTo(int64_t total, const std::string& what);
    // Shrinks the reservation to `total` bytes (nothing if it holds no more), and starts the
    // queued calls that fit now.
    void ShrinkTo(int64_t total);
    int64_t bytes() const { return bytes_; }
    void Release();

   private:
    friend class CallGate;
    CallGate* gate_ = nullptr;
    int64_t bytes_ = 0;
    std::string identity_;     // whose call this is, for the per-identity caps
    int64_t input_bytes_ = 0;  // of bytes_, counted as identity_'s upload (until admitted)
    bool uploading_ = true;    // not admitted to refine yet
  };

  // One open call of an identity; released when destroyed.
  class Ticket {
   public:
    Ticket() = default;
    ~Ticket() { Release(); }
    Ticket(Ticket&& other) noexcept;
    Ticket& operator=(Ticket&& other) noexcept;
    void Release();
    // Stops counting the call against its identity's limit; it stays open (open_calls,
    // WaitUntilIdle) until Release. For a call whose final status is being sent: the client
    // sees the call end as the status arrives, before the server is done with it, and a client
    // that starts its next call at once was refused as having one call too many (8 clients
    // calling one after another were told they had 16 open, in a loaded CI run).
    void EndForIdentity();

   private:
    friend class CallGate;
    CallGate* gate_ = nullptr;
    std::string identity_;
    bool counted_ = false;  // still counted against identity_
  };

  // Admits a new call from `identity`: UNAVAILABLE once StopAdmitting was called,
  // RESOURCE_EXHAUSTED (naming the identity, its limit and when to retry) when it already has
  // max_calls_per_identity calls open.
  absl::StatusOr<Ticket> Open(const std::string& identity);

  // A reservation of `bytes` for a new call of `identity` (RESOURCE_EXHAUSTED if they do not
  // fit, or its uploads would hold more than max_input_bytes_per_identity, or all its calls more
  // than max_bytes_per_identity). Until the call is admitted to refine, what it grows to counts
  // as its identity's upload.
  absl::StatusOr<Reservation> Reserve(int64_t bytes, const std::string& what,
                                      const std::string& identity = "");

  // Queues a call whose input is complete. As soon as a slot is free and `total_bytes` fit
  // (counting what `reservation` already holds), grows the reservation to them, takes the slot
  // and runs `start`: here if that is possible now, else on the thread that frees enough
  // (a refinement ending, a call finishing). Calls start in arrival order, except that a call
  // whose memory does not fit yet does not hold back later ones that fit. `reservation` must
  // stay valid until `start` has run or Withdraw returned true. Returns an id for Withdraw.
  // A call that could never fit (total_bytes above the whole budget) is the caller's to refuse
  // first (see FitsEver).
  // Among calls that fit, the one whose identity holds the fewest slots starts first (then
  // arrival order), and none whose identity holds max_slots_per_identity, or whose identity's
  // other calls and this one's total_bytes would hold more than max_bytes_per_identity.
  uint64_t Enqueue(const std::string& identity, Reservation* reservation, int64_t total_bytes,
                   std::function<void()> start);
  // Takes a queued call out: true if it had not started (its `start` will never run).
  bool Withdraw(uint64_t id);
  // Frees the slot taken for a started call of `identity`.
  void ReleaseSlot(const std::string& identity);

  // False when `bytes` exceed the whole budget.
  bool FitsEver(int64_t bytes) const;

  // From now on Open refuses with UNAVAILABLE (a draining server); open calls carry on.
  void StopAdmitting();
  bool admitting() const;
  // Waits until no call is open (or `deadline`); true if none is.
  bool WaitUntilIdle(std::chrono::steady_clock::time_point deadline);

  int open_calls() const;
  int running() const;                             // slots taken
  int running(const std::string& identity) const;  // slots taken by `identity`
  int64_t started_total() const;  // calls that have taken a slot since the gate was made
  int queued() const;
  int64_t reserved_bytes() const;
  int64_t held_bytes(const std::string& identity) const;  // what `identity`'s calls hold
  // True when `identity`'s calls other than one holding `own` bytes hold something, and with
  // that one grown to `total` bytes more than max_bytes_per_identity: the rule Reserve and
  // Enqueue apply, for a caller that says why a call waits.
  bool OverIdentityCap(const std::string& identity, int64_t own, int64_t total) const;
  const Config& config() const { return config_; }

 private:
  struct Waiter {
    uint64_t id;
    std::string identity;
    Reservation* reservation;
    int64_t total_bytes;
    std::function<void()> start;
  };
  // Starts every waiter that fits now; their start functions, to run unlocked.
  std::vector<std::function<void()>> Admit();
  int RunningLocked(const std::string& identity) const;  // slots `identity` holds (under mu_)
  void RunStarts(std::vector<std::function<void()>> starts);
  std::string Free() const;                         // "X free of Y" for messages (under mu_)
  void UncountLocked(const std::string& identity);  // one call fewer for `identity` (under mu_)
  // Takes `bytes` off `identity`'s uploads (under mu_).
  void UncountUploadLocked(const std::string& identity, int64_t bytes);
  // Adds `delta` to what `identity`'s calls hold (under mu_).
  void AddHeldLocked(const std::string& identity, int64_t delta);
  int64_t HeldLocked(const std::string& identity) const;
  // True when `identity`'s calls other than the one holding `own` bytes hold something, and with
  // it grown to `total` more than max_bytes_per_identity (under mu_).
  bool OverIdentityCapLocked(const std::string& identity, int64_t own, int64_t total) const;

  const Config config_;
  mutable std::mutex mu_;
  std::condition_variable idle_;
  bool admitting_ = true;
  int open_ = 0;
  std::map<std::string, int> per_identity_;
  int running_ = 0;
  std::map<std::string, int> running_per_identity_;
  std::map<std::string, int64_t> uploading_per_identity_;  // Reservation::input_bytes_ summed
  std::map<std::string, int64_t> held_per_identity_;       // Reservation::bytes_ summed
  int64_t started_ = 0;
  int64_t reserved_ = 0;
  std::list<Waiter> queue_;
  uint64_t next_waiter_ = 1;
};

}  // namespace tetrefine::server
