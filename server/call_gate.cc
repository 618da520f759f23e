#include "server/call_gate.h"

#include <utility>
#include <vector>

#include "absl/strings/str_cat.h"
#include "server/memory_budget.h"

namespace tetrefine::server {

CallGate::Reservation::Reservation(Reservation&& other) noexcept
    : gate_(std::exchange(other.gate_, nullptr)),
      bytes_(std::exchange(other.bytes_, 0)),
      identity_(std::move(other.identity_)),
      input_bytes_(std::exchange(other.input_bytes_, 0)),
      uploading_(std::exchange(other.uploading_, true)) {}

CallGate::Reservation& CallGate::Reservation::operator=(Reservation&& other) noexcept {
  if (this != &other) {
    Release();
    gate_ = std::exchange(other.gate_, nullptr);
    bytes_ = std::exchange(other.bytes_, 0);
    identity_ = std::move(other.identity_);
    input_bytes_ = std::exchange(other.input_bytes_, 0);
    uploading_ = std::exchange(other.uploading_, true);
  }
  return *this;
}

absl::Status CallGate::Reservation::GrowTo(int64_t total, const std::string& what) {
  if (gate_ == nullptr || total <= bytes_) return absl::OkStatus();
  {
    std::lock_guard<std::mutex> lock(gate_->mu_);
    const int64_t budget = gate_->config_.memory_budget_bytes;
    if (budget > 0 && gate_->reserved_ - bytes_ + total > budget) {
      return absl::ResourceExhaustedError(absl::StrCat(
          what, " needs ", HumanBytes(total), " of this server's memory budget and ", gate_->Free(),
          "; retry in a few seconds, when running calls have finished"));
    }
    if (gate_->OverIdentityCapLocked(identity_, bytes_, total)) {
      return absl::ResourceExhaustedError(absl::StrCat(
          what, " needs ", HumanBytes(total), " of this server's memory budget, and client ",
          identity_, "'s other calls hold ", HumanBytes(gate_->HeldLocked(identity_) - bytes_),
          " of the ", HumanBytes(gate_->config_.max_bytes_per_identity),
          " one client's calls may hold together (results not yet read count until read); retry "
          "when they have finished"));
    }
    const int64_t cap = gate_->config_.max_input_bytes_per_identity;
    if (uploading_ && cap > 0) {
      int64_t& held = gate_->uploading_per_identity_[identity_];
      // A client's only upload may take what the budget has (a large volume); beside others of
      // the same client, the sum stays within the cap.
      const int64_t others = held - input_bytes_;
      if (others > 0 && others + total > cap) {
        if (held == 0) gate_->uploading_per_identity_.erase(identity_);
        return absl::ResourceExhaustedError(absl::StrCat(
            what, " needs ", HumanBytes(total), " of this server's memory budget, and client ",
            identity_, "'s other uploads hold ", HumanBytes(others), " of the ", HumanBytes(cap),
            " one client's uploads may hold (half the budget); retry when they have finished"));
      }
      held += total - input_bytes_;
      input_bytes_ = total;
    }
    gate_->reserved_ += total - bytes_;
    gate_->AddHeldLocked(identity_, total - bytes_);
    bytes_ = total;
  }
  return absl::OkStatus();
}

void CallGate::Reservation::ShrinkTo(int64_t total) {
  if (gate_ == nullptr || total >= bytes_) return;
  std::vector<std::function<void()>> starts;
  {
    std::lock_guard<std::mutex> lock(gate_->mu_);
    gate_->reserved_ -= bytes_ - std::max<int64_t>(total, 0);
    gate_->AddHeldLocked(identity_, std::max<int64_t>(total, 0) - bytes_);
    bytes_ = std::max<int64_t>(total, 0);
    starts = gate_->Admit();
  }
  gate_->RunStarts(std::move(starts));
}

void CallGate::Reservation::Release() {
  if (gate_ == nullptr) return;
  std::vector<std::function<void()>> starts;
  {
    std::lock_guard<std::mutex> lock(gate_->mu_);
    gate_->reserved_ -= bytes_;
    gate_->AddHeldLocked(identity_, -bytes_);
    gate_->UncountUploadLocked(identity_, std::exchange(input_bytes_, 0));
    starts = gate_->Admit();
  }
  CallGate* gate = std::exchange(gate_, nullptr);
  bytes_ = 0;
  gate->RunStarts(std::move(starts));
}

CallGate::Ticket::Ticket(Ticket&& other) noexcept
    : gate_(std::exchange(other.gate_, nullptr)),
      identity_(std::move(other.identity_)),
      counted_(std::exchange(other.counted_, false)) {}

CallGate::Ticket& CallGate::Ticket::operator=(Ticket&& other) noexcept {
  if (this != &other) {
    Release();
    gate_ = std::exchange(other.gate_, nullptr);
    identity_ = std::move(other.identity_);
    counted_ = std::exchange(other.counted_, false);
  }
  return *this;
}

void CallGate::UncountLocked(const std::string& identity) {
  if (auto it = per_identity_.find(identity); it != per_identity_.end() && --it->second == 0) {
    per_identity_.erase(it);
  }
}

void CallGate::UncountUploadLocked(const std::string& identity, int64_t bytes) {
  if (bytes == 0) return;
  if (auto it = uploading_per_identity_.find(identity); it != uploading_per_identity_.end()) {
    it->second -= bytes;
    if (it->second <= 0) uploading_per_identity_.erase(it);
  }
}

void CallGate::AddHeldLocked(const std::string& identity, int64_t delta) {
  if (delta == 0) return;
  int64_t& held = held_per_identity_[identity];
  held += delta;
  if (held <= 0) held_per_identity_.erase(identity);
}

int64_t CallGate::HeldLocked(const std::string& identity) const {
  const auto it = held_per_identity_.find(identity);
  return it == held_per_identity_.end() ? 0 : it->second;
}

bool CallGate::OverIdentityCapLocked(const std::string& identity, int64_t own,
                                     int64_t total) const {
  const int64_t cap = config_.max_bytes_per_identity;
  if (cap <= 0) return false;
  const int64_t others = HeldLocked(identity) - own;
  return others > 0 && others + total > cap;
}

void CallGate::Ticket::EndForIdentity() {
  if (gate_ == nullptr || !counted_) return;
  std::lock_guard<std::mutex> lock(gate_->mu_);
  gate_->UncountLocked(identity_);
  counted_ = false;
}

void CallGate::Ticket::Release() {
  if (gate_ == nullptr) return;
  CallGate* gate = std::exchange(gate_, nullptr);
  std::lock_guard<std::mutex> lock(gate->mu_);
  --gate->open_;
  if (std::exchange(counted_, false)) gate->UncountLocked(identity_);
  // Under the lock: a waiter may destroy the gate as soon as it sees no open call.
  gate->idle_.notify_all();
}

absl::StatusOr<CallGate::Ticket> CallGate::Open(const std::string& identity) {
  std::lock_guard<std::mutex> lock(mu_);
  if (!admitting_) {
    return absl::UnavailableError("this server is shutting down; retry on another");
  }
  int& calls = per_identity_[identity];
  if (config_.max_calls_per_identity > 0 && calls >= config_.max_calls_per_identity) {
    return absl::ResourceExhaustedError(absl::StrCat(
        "client ", identity, " already has ", calls, " Refine calls open, this server's limit",
        " per client (--max_calls_per_identity); retry when one of them has finished"));
  }
  ++calls;
  ++open_;
  Ticket ticket;
  ticket.gate_ = this;
  ticket.identity_ = identity;
  ticket.counted_ = true;
  return ticket;
}

absl::StatusOr<CallGate::Reservation> CallGate::Reserve(int64_t bytes, const std::string& what,
                                                        const std::string& identity) {
  Reservation reservation;
  reservation.gate_ = this;
  reservation.identity_ = identity;
  absl::Status status = reservation.GrowTo(bytes, what);
  if (!status.ok()) {
    reservation.gate_ = nullptr;
    return status;
  }
  return reservation;
}

bool CallGate::FitsEver(int64_t bytes) const {
  return config_.memory_budget_bytes <= 0 || bytes <= config_.memory_budget_bytes;
}

uint64_t CallGate::Enqueue(const std::string& identity, Reservation* reservation,
                           int64_t total_bytes, std::function<void()> start) {
  std::vector<std::function<void()>> starts;
  uint64_t id;
  {
    std::lock_guard<std::mutex> lock(mu_);
    id = next_waiter_++;
    queue_.push_back(Waiter{.id = id,
                            .identity = identity,
                            .reservation = reservation,
                            .total_bytes = total_bytes,
                            .start = std::move(start)});
    starts = Admit();
  }
  RunStarts(std::move(starts));
  return id;
}

bool CallGate::Withdraw(uint64_t id) {
  std::lock_guard<std::mutex> lock(mu_);
  for (auto it = queue_.begin(); it != queue_.end(); ++it) {
    if (it->id == id) {
      queue_.erase(it);
      return true;
    }
  }
  return false;
}

void CallGate::ReleaseSlot(const std::string& identity) {
  std::vector<std::function<void()>> starts;
  {
    std::lock_guard<std::mutex> lock(mu_);
    --running_;
    if (auto it = running_per_identity_.find(identity);
        it != running_per_identity_.end() && --it->second <= 0) {
      running_per_identity_.erase(it);
    }
    starts = Admit();
  }
  RunStarts(std::move(starts));
}

int CallGate::running(const std::string& identity) const {
  std::lock_guard<std::mutex> lock(mu_);
  return RunningLocked(identity);
}

int CallGate::RunningLocked(const std::string& identity) const {
  const auto it = running_per_identity_.find(identity);
  return it == running_per_identity_.end() ? 0 : it->second;
}

std::vector<std::function<void()>> CallGate::Admit() {
  std::vector<std::function<void()>> starts;
  const int64_t budget = config_.memory_budget_bytes;
  while (running_ < config_.slots) {
    // The waiter that fits and whose identity holds the fewest slots, the earliest among equals;
    // a call whose memory does not fit yet does not hold back later ones that fit.
    auto best = queue_.end();
    int best_held = 0;
    for (auto it = queue_.begin(); it != queue_.end(); ++it) {
      const int h = RunningLocked(it->identity);
      if (config_.max_slots_per_identity > 0 && h >= config_.max_slots_per_identity) continue;
      if (best != queue_.end() && h >= best_held) continue;
      const int64_t more = std::max<int64_t>(0, it->total_bytes - it->reservation->bytes_);
      if (budget > 0 && reserved_ + more > budget) continue;
      const Reservation& r = *it->reservation;
      if (OverIdentityCapLocked(r.identity_, r.bytes_, r.bytes_ + more)) continue;
      best = it;
      best_held = h;
    }
    if (best == queue_.end()) break;
    Reservation& r = *best->reservation;
    const int64_t more = std::max<int64_t>(0, best->total_bytes - r.bytes_);
    reserved_ += more;
    AddHeldLocked(r.identity_, more);
    r.bytes_ += more;
    // Admitted: no longer an upload.
    UncountUploadLocked(r.identity_, std::exchange(r.input_bytes_, 0));
    r.uploading_ = false;
    ++running_;
    ++running_per_identity_[best->identity];
    ++started_;
    starts.push_back(std::move(best->start));
    queue_.erase(best);
  }
  return starts;
}

void CallGate::RunStarts(std::vector<std::function<void()>> starts) {
  for (std::function<void()>& start : starts) start();
}

std::string CallGate::Free() const {
  return absl::StrCat(HumanBytes(config_.memory_budget_bytes - reserved_), " of ",
                      HumanBytes(config_.memory_budget_bytes), " are free");
}

void CallGate::StopAdmitting() {
  std::lock_guard<std::mutex> lock(mu_);
  admitting_ = false;
}

bool CallGate::admitting() const {
  std::lock_guard<std::mutex> lock(mu_);
  return admitting_;
}

bool CallGate::WaitUntilIdle(std::chrono::steady_clock::time_point deadline) {
  std::unique_lock<std::mutex> lock(mu_);
  if (deadline == std::chrono::steady_clock::time_point::max()) {
    idle_.wait(lock, [&] { return open_ == 0; });
    return true;
  }
  return idle_.wait_until(lock, deadline, [&] { return open_ == 0; });
}

int CallGate::open_calls() const {
  std::lock_guard<std::mutex> lock(mu_);
  return open_;
}

int CallGate::running() const {
  std::lock_guard<std::mutex> lock(mu_);
  return running_;
}

int64_t CallGate::started_total() const {
  std::lock_guard<std::mutex> lock(mu_);
  return started_;
}

int CallGate::queued() const {
  std::lock_guard<std::mutex> lock(mu_);
  return static_cast<int>(queue_.size());
}

int64_t CallGate::reserved_bytes() const {
  std::lock_guard<std::mutex> lock(mu_);
  return reserved_;
}

int64_t CallGate::held_bytes(const std::string& identity) const {
  std::lock_guard<std::mutex> lock(mu_);
  return HeldLocked(identity);
}

bool CallGate::OverIdentityCap(const std::string& identity, int64_t own, int64_t total) const {
  std::lock_guard<std::mutex> lock(mu_);
  return OverIdentityCapLocked(identity, own, total);
}

}  // namespace tetrefine::server
