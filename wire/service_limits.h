#pragma once

#include <cstdint>

namespace tetrefine::wire {

// What one server accepts, as GetServerInfo advertises it (tetrefine.v1.ServerLimits). Sizes and
// options are checked against declared values before anything is allocated or computed, so that
// no single call can ask for unbounded memory or CPU; the time limits bound how long any call
// can hold what it was given.
struct ServiceLimits {
  int64_t max_voxels = int64_t{1} << 28;         // voxels of the volume (slab) sent
  int64_t max_input_tets = 10'000'000;           // input tets; input vertices: 4 times this
  int64_t max_output_tets = 50'000'000;          // the largest (and default) tet budget
  int max_concurrent_refinements = 4;            // refinements running at once
  int64_t max_message_bytes = int64_t{4} << 20;  // largest request message

  // Per-call work caps. A request above one is RESOURCE_EXHAUSTED naming the option and the cap.
  // Why these defaults: 100 iterations is six times the core's default of 16 (refinement stops
  // at the tet budget or the quality floor long before); lattice order 16 samples 969 points a
  // tet; 2e8 lattice points is six times the default check (order 8 on 200 000 tets = 3.3e7),
  // a few seconds of one core.
  int max_iterations = 100;
  int max_lattice_n = 16;
  int64_t max_lattice_points = 200'000'000;

  // Time limits of every Refine call, seconds. 0 (only in tests and the embedded service):
  // none. The network server's defaults are its flags' (server/server_flags.cc).
  double max_call_seconds = 0;        // the whole call, whatever the client's deadline
  double input_deadline_seconds = 0;  // from the call's start until its input is complete
  double idle_timeout_seconds = 0;    // the longest pause between request messages
  double write_stall_seconds = 0;     // the longest wait for the client to take a response
  double queue_seconds = 0;           // the longest wait for a refinement slot and memory

  // Open Refine calls (reading, queued, refining or writing) of one client identity; 0: no limit.
  int max_calls_per_identity = 0;
  // Memory the calls may reserve, bytes; 0: not budgeted. A call reserves its worst case
  // (server/memory_budget.h) at the rate of bytes_per_output_tet for its tet budget.
  int64_t memory_budget_bytes = 0;
  int64_t bytes_per_output_tet = 0;
};

// Barycentric lattice points of order n inside one tet: (n + 1)(n + 2)(n + 3) / 6.
constexpr int64_t LatticePointsPerTet(int64_t n) { return (n + 1) * (n + 2) * (n + 3) / 6; }

}  // namespace tetrefine::wire
