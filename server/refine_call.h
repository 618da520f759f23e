#pragma once

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <string>

#include "grpcpp/grpcpp.h"
#include "server/call_gate.h"
#include "server/log_rate_limit.h"
#include "server/refiner_service.h"
#include "server/watchdog.h"
#include "tetrefine/v1/tetrefine.pb.h"
#include "wire/request_reader.h"

namespace tetrefine::server {

// One Refine call, from first request to status, as a gRPC callback reactor.
//
//   input    reads and checks each request message as it arrives (reserving memory as the
//            headers declare it), bounded by the input deadline and the idle timeout; after
//            end_of_input it waits for the client to close the stream (a message instead is
//            INVALID_ARGUMENT).
//   queued   waits up to queue_seconds for a refinement slot and the memory of its worst case.
//   refining runs core Refine on a thread of its own, streaming iteration statistics; stops
//            promptly on cancellation, the client's deadline or the server's max_call_seconds.
//   writing  sends the result; the slot is already free, and a response the client does not
//            take within write_stall_seconds cancels the call.
//
// Exactly one party finishes the call: before the refinement starts, whichever event ends it
// (an error, a time limit, a cancellation); after, the refinement's own thread. gRPC reactor
// methods are never called with mu_ held (gRPC may run OnCancel inline inside them).
class RefineCall final : public grpc::ServerBidiReactor<v1::RefineRequest, v1::RefineResponse>,
                         public std::enable_shared_from_this<RefineCall> {
 public:
  // What calls share with their service, which outlives them.
  struct Environment {
    const ServiceConfig* config;
    CallGate* gate;
    Watchdog* watchdog;
    LogRateLimit* refusal_log;  // access lines of calls refused at arrival
  };

  // A new call; it keeps itself alive until gRPC is done with it (OnDone) and its refinement
  // thread, if any, has ended.
  static RefineCall* Start(grpc::CallbackServerContext* context, const Environment& environment);
  ~RefineCall() override;

  void OnReadDone(bool ok) override;
  void OnWriteDone(bool ok) override;
  void OnCancel() override;
  void OnDone() override;

  RefineCall(grpc::CallbackServerContext* context, const Environment& environment);

 private:
  using Clock = std::chrono::steady_clock;
  enum class Phase { kInput, kClosing, kQueued, kRefining, kFinished };
  enum class Timer { kInput, kQueue, kCall, kStall };

  void Begin();
  // Claims the right to finish (under mu_): false if another party already has it.
  bool ClaimFinishLocked();
  // Logs, records metrics and sends `status` (after ClaimFinishLocked, without mu_ held).
  void SendStatus(const grpc::Status& status, std::optional<int> retry_after_ms = std::nullopt);
  void Admit();
  void StartRefinement();
  void Work();
  grpc::Status Refine();
  // Sends one response and waits until the client has taken it: false when the call was cancelled
  // or the client stopped reading for write_stall_seconds.
  bool BlockingWrite(const v1::RefineResponse& response);
  // Whatever stops the refinement: a cancel, the server's or the client's deadline, a stall.
  bool Interrupted() const;
  grpc::Status InterruptedStatus(const std::string& during) const;
  void Schedule(Timer timer, Clock::time_point when);
  void OnTimer(Timer timer);
  std::string WhyNotAdmitted() const;

  grpc::CallbackServerContext* const context_;
  const Environment env_;
  const wire::ServiceLimits& limits_;
  const Clock::time_point start_;

  // Released last (declared first): once it is gone the service may be destroyed.
  CallGate::Ticket ticket_;
  CallGate::Reservation reservation_;
  std::shared_ptr<RefineCall> self_;  // until OnDone
  std::string identity_ = "-";
  std::string peer_;  // gRPC forgets it once the call is cancelled

  mutable std::mutex mu_;
  std::condition_variable write_done_cv_;
  Phase phase_ = Phase::kInput;
  bool finish_claimed_ = false;
  v1::RefineRequest request_;
  wire::RequestReader reader_;
  std::optional<wire::RefineInput> input_;
  Clock::time_point last_read_;
  Clock::time_point input_deadline_ = Clock::time_point::max();
  Clock::time_point call_deadline_ = Clock::time_point::max();
  uint64_t waiter_ = 0;
  bool write_pending_ = false;
  bool write_ok_ = false;
  Watchdog::Id timers_[4] = {0, 0, 0, 0};

  std::atomic<bool> cancelled_{false};     // OnCancel ran
  std::atomic<bool> deadline_hit_{false};  // max_call_seconds passed
  std::atomic<bool> stalled_{false};       // the client did not take a response in time
  std::atomic<bool> broken_{false};        // a write failed
  double input_seconds_ = 0.0;
  int64_t tets_out_ = 0;
  int iterations_ = 0;
  bool slot_released_ = false;  // the refinement slot went back to the gate (Work's thread only)
  // Set by Admit: the reservation the refinement waits for, its input part and its tet budget.
  int64_t worst_case_bytes_ = 0;
  int64_t worst_case_input_bytes_ = 0;
  int64_t worst_case_tets_ = 0;
  bool admitted_ = false;  // past identity, quota and memory checks at arrival (for metrics)
};

}  // namespace tetrefine::server
