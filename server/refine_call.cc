#include "server/refine_call.h"

#include <algorithm>
#include <new>
#include <span>
#include <thread>
#include <utility>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "core/refine.h"
#include "server/memory_budget.h"
#include "server/metrics.h"
#include "spdlog/spdlog.h"
#include "wire/conversion.h"
#include "wire/response_writer.h"

namespace tetrefine::server {
namespace {

using Clock = std::chrono::steady_clock;

Clock::duration Seconds(double s) {
  return std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(s));
}

double SecondsBetween(Clock::time_point a, Clock::time_point b) {
  return std::chrono::duration<double>(b - a).count();
}

// Suggested delays before a retry, for grpc-retry-pushback-ms: a busy slot or memory frees when
// a running call ends (small ones take milliseconds, large ones seconds); a client over its own
// quota has to wait for one of its calls.
constexpr int kRetryBusyMs = 2000;

}  // namespace

RefineCall* RefineCall::Start(grpc::CallbackServerContext* context,
                              const Environment& environment) {
  auto call = std::make_shared<RefineCall>(context, environment);
  call->self_ = call;
  call->Begin();
  return call.get();
}

RefineCall::RefineCall(grpc::CallbackServerContext* context, const Environment& environment)
    : context_(context),
      env_(environment),
      limits_(environment.config->limits),
      start_(Clock::now()),
      reader_(environment.config->limits),
      last_read_(start_) {}

RefineCall::~RefineCall() {
  for (Watchdog::Id id : timers_) {
    if (id != 0) env_.watchdog->Cancel(id);
  }
}

void RefineCall::Begin() {
  peer_ = context_->peer();
  grpc::Status refusal;
  std::optional<int> retry_after;
  absl::StatusOr<std::string> identity = IdentifyCall(env_.config->access, *context_);
  if (!identity.ok()) {
    refusal = wire::ToGrpcStatus(identity.status());
  } else {
    identity_ = *identity;
    absl::StatusOr<CallGate::Ticket> ticket = env_.gate->Open(identity_);
    absl::StatusOr<CallGate::Reservation> reservation;
    if (ticket.ok()) {
      reservation =
          env_.gate->Reserve(OpenCallBytes(limits_.max_message_bytes), "a new call", identity_);
    }
    if (!ticket.ok() || !reservation.ok()) {
      const absl::Status& status = !ticket.ok() ? ticket.status() : reservation.status();
      refusal = wire::ToGrpcStatus(status);
      if (absl::IsResourceExhausted(status)) retry_after = kRetryBusyMs;
    } else {
      ticket_ = *std::move(ticket);
      reservation_ = *std::move(reservation);
      admitted_ = true;
    }
  }
  if (!refusal.ok()) {
    {
      std::lock_guard<std::mutex> lock(mu_);
      ClaimFinishLocked();
    }
    SendStatus(refusal, retry_after);
    return;
  }
  if (limits_.input_deadline_seconds > 0) {
    input_deadline_ = start_ + Seconds(limits_.input_deadline_seconds);
  }
  if (limits_.max_call_seconds > 0) {
    call_deadline_ = start_ + Seconds(limits_.max_call_seconds);
    Schedule(Timer::kCall, call_deadline_);
  }
  Clock::time_point check = input_deadline_;
  if (limits_.idle_timeout_seconds > 0) {
    check = std::min(check, start_ + Seconds(limits_.idle_timeout_seconds));
  }
  if (check != Clock::time_point::max()) Schedule(Timer::kInput, check);
  StartRead(&request_);
}

bool RefineCall::ClaimFinishLocked() {
  if (finish_claimed_) return false;
  finish_claimed_ = true;
  return true;
}

void RefineCall::SendStatus(const grpc::Status& status, std::optional<int> retry_after_ms) {
  int64_t bytes_in = 0, tets_in = 0;
  {
    std::lock_guard<std::mutex> lock(mu_);
    phase_ = Phase::kFinished;
    bytes_in = reader_.bytes_received();
    // The declared count of an input that never completed (or whose header was refused: an
    // operator sweep put 1e15 on the counter with one request) is not input.
    tets_in = reader_.complete() ? reader_.tets_declared() : 0;
  }
  // Only a delivered refinement counts: a call cancelled or out of time after its refinement
  // made tets but gave the client none.
  const int64_t tets_out = status.ok() ? tets_out_ : 0;
  const double seconds = SecondsBetween(start_, Clock::now());
  if (env_.config->metrics != nullptr) {
    env_.config->metrics->RecordCall({.code = status.error_code(),
                                      .admitted = admitted_,
                                      .seconds = seconds,
                                      .bytes_in = bytes_in,
                                      .tets_in = tets_in,
                                      .tets_out = tets_out});
  }
  // Calls refused at arrival (identity, quota, memory) are logged at most 20 a second, saying how
  // many were not (server/log_rate_limit.h).
  int64_t unlogged = 0;
  if (status.ok() || admitted_ || env_.refusal_log == nullptr ||
      env_.refusal_log->Allow(&unlogged)) {
    spdlog::info(
        "Refine peer={} identity={} bytes_in={} tets_in={} tets_out={} iterations={} "
        "duration={:.3f}s status={} {}{}",
        peer_, identity_, bytes_in, tets_in, tets_out, iterations_, seconds,
        absl::StatusCodeToString(static_cast<absl::StatusCode>(status.error_code())),
        status.error_message(), LogRateLimit::SuppressedNote(unlogged));
  }
  if (retry_after_ms.has_value()) {
    context_->AddTrailingMetadata("grpc-retry-pushback-ms", std::to_string(*retry_after_ms));
  }
  // Before Finish: a client that has the status may open its next call at once.
  ticket_.EndForIdentity();
  Finish(status);  // last: the call may be done with this object from here on
}

void RefineCall::OnReadDone(bool ok) {
  std::optional<grpc::Status> finish;
  std::optional<int> retry_after;
  bool read_more = false;
  bool admit = false;
  {
    std::lock_guard<std::mutex> lock(mu_);
    if (finish_claimed_ || (phase_ != Phase::kInput && phase_ != Phase::kClosing)) return;
    if (!ok) {
      if (phase_ == Phase::kClosing) {
        admit = true;  // the client closed the stream after end_of_input
      } else if (context_->IsCancelled()) {
        return;  // OnCancel finishes
      } else {
        ClaimFinishLocked();
        finish = wire::ToGrpcStatus(reader_.IncompleteError());
      }
    } else {
      last_read_ = Clock::now();
      absl::Status status = reader_.Add(request_);
      if (status.ok()) {
        // An input that could never fit is refused from its header. Otherwise the budget is
        // reserved as the input arrives, not as it is declared: a service sweep held a 2 GiB
        // server's whole budget for minutes with three calls that declared large volumes and
        // sent a byte every 10 s, and every other call was refused. Holding memory now costs
        // sending it. (The reader reserves its buffers' address space at the header; pages are
        // used as the data arrives.)
        const int64_t open = OpenCallBytes(limits_.max_message_bytes);
        const int64_t declared = reader_.DeclaredInputBytes();
        if (!env_.gate->FitsEver(open + declared)) {
          status = absl::ResourceExhaustedError(absl::StrCat(
              "the input this call declares (volume and mesh) needs ", HumanBytes(open + declared),
              ", more than this server's whole memory budget of ",
              HumanBytes(env_.gate->config().memory_budget_bytes), " (--memory_budget_bytes)"));
        } else {
          status = reservation_.GrowTo(open + std::min(declared, reader_.bytes_received()),
                                       "the input this call has sent (volume and mesh)");
          if (!status.ok()) retry_after = kRetryBusyMs;
        }
      }
      if (!status.ok()) {
        ClaimFinishLocked();
        finish = wire::ToGrpcStatus(status);
      } else {
        if (reader_.complete()) phase_ = Phase::kClosing;
        read_more = true;
      }
    }
  }
  if (finish.has_value()) {
    SendStatus(*finish, retry_after);
  } else if (read_more) {
    StartRead(&request_);
  } else if (admit) {
    Admit();
  }
}

void RefineCall::Admit() {
  std::optional<grpc::Status> refusal;
  int64_t total = 0;
  Watchdog::Id input_timer = 0;
  {
    std::lock_guard<std::mutex> lock(mu_);
    if (finish_claimed_) return;
    input_seconds_ = SecondsBetween(start_, Clock::now());
    input_ = reader_.Take();
    const wire::RequestOptions& o = input_->options;
    const int64_t max_tets = o.send_max_tets ? o.refine.max_tets : limits_.max_output_tets;
    const int64_t out_tets =
        WorstCaseOutputTets(reader_.tets_declared(), o.refine.max_iterations, max_tets);
    const int64_t base = OpenCallBytes(limits_.max_message_bytes) + reader_.DeclaredInputBytes();
    const int64_t per_tet = limits_.bytes_per_output_tet;
    total = base + out_tets * per_tet;
    worst_case_bytes_ = total;
    worst_case_input_bytes_ = base;
    worst_case_tets_ = out_tets;
    if (!env_.gate->FitsEver(total)) {
      ClaimFinishLocked();
      const int64_t budget = env_.gate->config().memory_budget_bytes;
      const int64_t fits = per_tet > 0 ? std::max<int64_t>(0, (budget - base) / per_tet) : 0;
      refusal = grpc::Status(
          grpc::StatusCode::RESOURCE_EXHAUSTED,
          absl::StrCat("this call may need ", HumanBytes(total), " (input ", HumanBytes(base),
                       ", and up to ", out_tets, " output tets at ", per_tet,
                       " bytes each), more than this server's whole memory budget of ",
                       HumanBytes(budget), "; ask for max_tets of at most ", fits,
                       " (or fewer max_iterations)"));
    } else {
      phase_ = Phase::kQueued;
    }
    std::swap(input_timer, timers_[static_cast<int>(Timer::kInput)]);
  }
  if (input_timer != 0) env_.watchdog->Cancel(input_timer);
  if (refusal.has_value()) {
    SendStatus(*refusal);
    return;
  }
  std::weak_ptr<RefineCall> weak = weak_from_this();
  const uint64_t waiter = env_.gate->Enqueue(identity_, &reservation_, total, [weak] {
    if (std::shared_ptr<RefineCall> call = weak.lock()) call->StartRefinement();
  });
  {
    std::lock_guard<std::mutex> lock(mu_);
    waiter_ = waiter;
  }
  if (limits_.queue_seconds > 0) {
    Schedule(Timer::kQueue, Clock::now() + Seconds(limits_.queue_seconds));
  } else if (env_.gate->Withdraw(waiter)) {
    OnTimer(Timer::kQueue);  // no wait allowed: refused now
  }
}

std::string RefineCall::WhyNotAdmitted() const {
  const CallGate& gate = *env_.gate;
  if (gate.running() >= gate.config().slots) {
    return absl::StrCat("all ", gate.config().slots,
                        " refinement slots of this server are busy (--max_concurrent)");
  }
  const int cap = gate.config().max_slots_per_identity;
  if (const int held = gate.running(identity_); cap > 0 && held >= cap) {
    return absl::StrCat("client ", identity_, " already holds ", held, " of the ",
                        gate.config().slots,
                        " refinement slots of this server, as many as one client may "
                        "(--max_slots_per_identity), and the rest are kept for other clients");
  }
  if (gate.OverIdentityCap(identity_, reservation_.bytes(), worst_case_bytes_)) {
    const int64_t mine = gate.held_bytes(identity_) - reservation_.bytes();
    return absl::StrCat("client ", identity_, "'s other calls hold ", HumanBytes(mine), " of the ",
                        HumanBytes(gate.config().max_bytes_per_identity),
                        " one client's calls may hold together (results not yet read count until "
                        "read), and this call's worst case is ",
                        HumanBytes(worst_case_bytes_),
                        "; read their results, or retry when they have finished");
  }
  // What this call needs and what would fit now (a service sweep saw small calls refused beside
  // a large one with only the other calls' total: nothing said the call's own default tet budget
  // was the reason, or that a max_tets would have run at once).
  const int64_t budget = gate.config().memory_budget_bytes;
  const int64_t others = gate.reserved_bytes() - reservation_.bytes();
  const int64_t per_tet = limits_.bytes_per_output_tet;
  const int64_t fits_now =
      per_tet > 0 ? std::max<int64_t>(0, (budget - others - worst_case_input_bytes_) / per_tet) : 0;
  return absl::StrCat("this call's worst case, ", HumanBytes(worst_case_bytes_), " (input ",
                      HumanBytes(worst_case_input_bytes_), ", and up to ", worst_case_tets_,
                      " output tets at ", per_tet, " bytes each), does not fit the memory left: ",
                      HumanBytes(std::max<int64_t>(0, budget - others)), " of ", HumanBytes(budget),
                      " are free (--memory_budget_bytes); a max_tets of at most ", fits_now,
                      " fits now");
}

void RefineCall::StartRefinement() {
  Watchdog::Id queue_timer = 0;
  {
    std::lock_guard<std::mutex> lock(mu_);
    phase_ = Phase::kRefining;
    std::swap(queue_timer, timers_[static_cast<int>(Timer::kQueue)]);
  }
  if (queue_timer != 0) env_.watchdog->Cancel(queue_timer);
  std::thread([call = shared_from_this()] { call->Work(); }).detach();
}

void RefineCall::Work() {
  grpc::Status status;
  try {
    status = Refine();
  } catch (const std::bad_alloc&) {
    // Refine catches a failed allocation of the refinement itself; this one came while the
    // call prepared it or wrote its result.
    if (!slot_released_) env_.gate->ReleaseSlot(identity_);
    slot_released_ = true;
    status = grpc::Status(grpc::StatusCode::RESOURCE_EXHAUSTED,
                          "out of memory while preparing or writing this call's result: this "
                          "server could not allocate more; ask for less or retry");
  }
  {
    std::lock_guard<std::mutex> lock(mu_);
    finish_claimed_ = true;  // from the start of the refinement, only this thread finishes
  }
  SendStatus(status);
}

bool RefineCall::Interrupted() const {
  return cancelled_.load() || deadline_hit_.load() || stalled_.load() || broken_.load() ||
         Clock::now() >= call_deadline_;
}

grpc::Status RefineCall::InterruptedStatus(const std::string& during) const {
  if (stalled_.load()) {
    return grpc::Status(
        grpc::StatusCode::DEADLINE_EXCEEDED,
        absl::StrCat("the client took no response message for ", limits_.write_stall_seconds,
                     " s (--write_stall_seconds) during ", during));
  }
  if (deadline_hit_.load() || Clock::now() >= call_deadline_) {
    return grpc::Status(
        grpc::StatusCode::DEADLINE_EXCEEDED,
        absl::StrCat("this call ran into this server's limit of ", limits_.max_call_seconds,
                     " s a call (--max_call_seconds) during ", during,
                     "; ask for less work (max_tets, epsilon, max_iterations, lattice_n)"));
  }
  if (std::chrono::system_clock::now() >= context_->deadline()) {
    return grpc::Status(grpc::StatusCode::DEADLINE_EXCEEDED,
                        absl::StrCat("deadline exceeded during ", during));
  }
  return grpc::Status(grpc::StatusCode::CANCELLED, absl::StrCat("cancelled during ", during));
}

grpc::Status RefineCall::Refine() {
  const wire::RequestOptions request_options = input_->options;
  RefineOptions options = wire::ToCoreOptions(request_options, limits_);
  options.threads = env_.config->refine_threads;
  wire::ResponseWriter writer(request_options.response_chunk_bytes,
                              [this](const v1::RefineResponse& r) { return BlockingWrite(r); });
  int iterations_done = 0;
  options.on_iteration = [&](const IterationStats& stats, const Mesh& mesh) {
    iterations_done = stats.iteration;
    if (broken_.load()) return;
    bool ok = writer.WriteIterationStats(stats);
    if (ok && request_options.stream_every_iteration) {
      ok = writer.WriteMesh(stats.iteration, /*final=*/false, mesh, {}, {});
    }
    if (!ok) broken_.store(true);
  };
  options.should_cancel = [this] { return Interrupted(); };

  absl::StatusOr<RefineResult> result;
  {
    ServiceMetrics::InFlight in_flight(env_.config->metrics.get());
    // An allocation that fails ends this call, not the process: uncaught, std::bad_alloc
    // terminated the server and every call in it (an outside review, 2026-11-29: a server under
    // `ulimit -v`, one request at a small epsilon). The core holds no lock or shared state
    // across an allocation, and TBB carries the exception out of its parallel loops; what the
    // call allocated is freed on the way.
    try {
      result = tetrefine::Refine(input_->volume, input_->mesh, options);
    } catch (const std::bad_alloc&) {
      result = absl::ResourceExhaustedError(absl::StrCat(
          "out of memory during the refinement, after ", iterations_done,
          " iterations: this server could not allocate more (its memory limit, or another "
          "call's share of it); ask for less (a larger epsilon, a lower max_tets) or retry"));
    }
  }
  // The CPU work is done: the slot goes to the next call while this one writes its result.
  env_.gate->ReleaseSlot(identity_);
  slot_released_ = true;
  input_.reset();
  if (!result.ok()) return wire::ToGrpcStatus(result.status());
  iterations_ = static_cast<int>(result->iterations.size());
  tets_out_ = static_cast<int64_t>(result->mesh.tets.size());
  // The worst case reserved at admission (the input, and up to max_tets output tets; by default
  // 90% of the budget) is more than what the result holds while it is written: the input is
  // gone, and the output has its real size. A finished call that a client did not read kept the
  // worst case for the write stall's minute, and other clients were refused for memory (an
  // outside review, 2026-11-28).
  reservation_.ShrinkTo(tets_out_ * limits_.bytes_per_output_tet);
  if (result->stop_reason == StopReason::kCancelled || Interrupted()) {
    return InterruptedStatus(absl::StrCat("refinement, after ", iterations_, " iterations"));
  }
  if (!request_options.skip_final_mesh &&
      !writer.WriteMesh(iterations_, /*final=*/true, result->mesh,
                        std::span<const int32_t>(result->tet_iteration),
                        std::span<const float>(result->tet_quality),
                        std::span<const uint32_t>(result->tet_parent))) {
    return InterruptedStatus("output");
  }
  const wire::ServiceSummary service{.max_tets = options.max_tets,
                                     .input_seconds = input_seconds_,
                                     .total_seconds = SecondsBetween(start_, Clock::now())};
  if (!writer.WriteSummary(*result, service, reader_.tets_declared())) {
    return InterruptedStatus("output");
  }
  return grpc::Status::OK;
}

bool RefineCall::BlockingWrite(const v1::RefineResponse& response) {
  if (Interrupted()) return false;
  {
    std::lock_guard<std::mutex> lock(mu_);
    write_pending_ = true;
    write_ok_ = false;
  }
  if (limits_.write_stall_seconds > 0) {
    Schedule(Timer::kStall, Clock::now() + Seconds(limits_.write_stall_seconds));
  }
  StartWrite(&response);
  bool ok = false;
  Watchdog::Id stall_timer = 0;
  {
    std::unique_lock<std::mutex> lock(mu_);
    write_done_cv_.wait(lock, [&] { return !write_pending_; });
    ok = write_ok_;
    std::swap(stall_timer, timers_[static_cast<int>(Timer::kStall)]);
  }
  if (stall_timer != 0) env_.watchdog->Cancel(stall_timer);
  if (!ok) broken_.store(true);
  return ok;
}

void RefineCall::OnWriteDone(bool ok) {
  {
    std::lock_guard<std::mutex> lock(mu_);
    write_pending_ = false;
    write_ok_ = ok;
  }
  write_done_cv_.notify_all();
}

void RefineCall::OnCancel() {
  cancelled_.store(true);
  bool finish = false;
  bool withdraw = false;
  uint64_t waiter = 0;
  std::string during = "input";
  {
    std::lock_guard<std::mutex> lock(mu_);
    if (finish_claimed_) return;
    if (phase_ == Phase::kInput || phase_ == Phase::kClosing) {
      finish = ClaimFinishLocked();
    } else if (phase_ == Phase::kQueued) {
      withdraw = true;
      waiter = waiter_;
      during = "the wait for a refinement slot";
    }
  }
  if (withdraw && waiter != 0 && env_.gate->Withdraw(waiter)) {
    std::lock_guard<std::mutex> lock(mu_);
    finish = ClaimFinishLocked();
  }
  if (finish) SendStatus(InterruptedStatus(during));
}

void RefineCall::OnDone() {
  std::shared_ptr<RefineCall> keep = std::move(self_);
  // `keep` may be the last reference: this object goes when the function returns.
}

void RefineCall::Schedule(Timer timer, Clock::time_point when) {
  std::weak_ptr<RefineCall> weak = weak_from_this();
  const Watchdog::Id id = env_.watchdog->Schedule(when, [weak, timer] {
    if (std::shared_ptr<RefineCall> call = weak.lock()) call->OnTimer(timer);
  });
  Watchdog::Id old = 0;
  {
    std::lock_guard<std::mutex> lock(mu_);
    old = std::exchange(timers_[static_cast<int>(timer)], id);
  }
  if (old != 0) env_.watchdog->Cancel(old);
}

void RefineCall::OnTimer(Timer timer) {
  const Clock::time_point now = Clock::now();
  std::optional<grpc::Status> finish;
  std::optional<int> retry_after;
  bool cancel_write = false;
  std::optional<Clock::time_point> again;
  switch (timer) {
    case Timer::kInput: {
      std::lock_guard<std::mutex> lock(mu_);
      if (finish_claimed_ || (phase_ != Phase::kInput && phase_ != Phase::kClosing)) return;
      const Clock::time_point idle_end = limits_.idle_timeout_seconds > 0
                                             ? last_read_ + Seconds(limits_.idle_timeout_seconds)
                                             : Clock::time_point::max();
      const std::string received = absl::StrCat(reader_.messages_received(), " request messages (",
                                                reader_.bytes_received(), " bytes) received");
      if (now >= input_deadline_) {
        ClaimFinishLocked();
        finish = grpc::Status(
            grpc::StatusCode::DEADLINE_EXCEEDED,
            absl::StrCat("the input was not complete ", limits_.input_deadline_seconds,
                         " s after the call began (--input_deadline_seconds); ", received,
                         ". Send the whole request, end_of_input, and close the stream"));
      } else if (now >= idle_end) {
        ClaimFinishLocked();
        finish = grpc::Status(
            grpc::StatusCode::DEADLINE_EXCEEDED,
            phase_ == Phase::kClosing
                ? absl::StrCat("end_of_input arrived but the client did not close the stream for ",
                               limits_.idle_timeout_seconds, " s (--idle_timeout_seconds)")
                : absl::StrCat("no request message for ", limits_.idle_timeout_seconds,
                               " s (--idle_timeout_seconds); ", received));
      } else {
        again = std::min(input_deadline_, idle_end);
      }
      break;
    }
    case Timer::kQueue: {
      // Reached with the call already withdrawn (no wait allowed), or to withdraw it now.
      uint64_t waiter = 0;
      {
        std::lock_guard<std::mutex> lock(mu_);
        if (finish_claimed_ || phase_ != Phase::kQueued) return;
        waiter = waiter_;
      }
      const bool withdrawn = limits_.queue_seconds <= 0 || env_.gate->Withdraw(waiter);
      if (!withdrawn) return;  // it has just started
      std::lock_guard<std::mutex> lock(mu_);
      if (!ClaimFinishLocked()) return;
      finish = grpc::Status(
          grpc::StatusCode::RESOURCE_EXHAUSTED,
          absl::StrCat(WhyNotAdmitted(),
                       limits_.queue_seconds > 0 ? absl::StrCat(" (waited ", limits_.queue_seconds,
                                                                " s, --queue_seconds)")
                                                 : std::string(),
                       "; retry in a few seconds"));
      retry_after = kRetryBusyMs;
      break;
    }
    case Timer::kCall: {
      deadline_hit_.store(true);
      uint64_t waiter = 0;
      bool queued = false;
      {
        std::lock_guard<std::mutex> lock(mu_);
        if (finish_claimed_) {
          cancel_write = write_pending_;  // the refinement's thread finishes
        } else if (phase_ == Phase::kInput || phase_ == Phase::kClosing) {
          ClaimFinishLocked();
          finish = InterruptedStatus("input");
        } else if (phase_ == Phase::kQueued) {
          queued = true;
          waiter = waiter_;
        } else {
          cancel_write = write_pending_;
        }
      }
      if (queued && env_.gate->Withdraw(waiter)) {
        std::lock_guard<std::mutex> lock(mu_);
        if (ClaimFinishLocked()) finish = InterruptedStatus("the wait for a refinement slot");
      }
      break;
    }
    case Timer::kStall: {
      std::lock_guard<std::mutex> lock(mu_);
      if (!write_pending_) return;
      stalled_.store(true);
      cancel_write = true;
      break;
    }
  }
  if (again.has_value()) Schedule(Timer::kInput, *again);
  if (cancel_write) {
    spdlog::warn("Refine peer={} identity={}: {}", peer_, identity_,
                 stalled_.load() ? "the client stopped reading; cancelling the call"
                                 : "max_call_seconds passed while writing; cancelling the call");
    context_->TryCancel();
  }
  if (finish.has_value()) SendStatus(*finish, retry_after);
}

}  // namespace tetrefine::server
