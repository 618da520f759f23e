#pragma once

#include <string>
#include <vector>

#include "client/refine_client.h"
#include "core/mesh.h"
#include "core/refine.h"
#include "core/volume.h"
#include "wire/service_limits.h"

namespace tetrefine::hardening {

// One refinement a client asks for, and what core Refine gives for it in this process.
struct Workload {
  std::string name;
  Volume volume;
  Mesh mesh;
  client::RefineRequestOptions options;
};

// Small refinements of a few milliseconds each, unlike one another: whole volumes and a slab,
// several voxel types, both orientation policies, per-vertex values.
const std::vector<Workload>& SmallWorkloads();

// 135k tets with a tolerance no edge meets: two iterations (about 4.4M tets, seconds) stopped
// by a 20M-tet budget, then a lattice check of every output tet that runs for about a minute:
// work that only cancellation ends early. The final mesh is not sent.
const Workload& HeavyWorkload();

// HeavyWorkload for one iteration that splits every edge, with the final mesh sent: a result of
// 1.08M tets, tens of MB, far more than a connection's flow-control window holds for a client
// that never reads.
Workload BigResultWorkload();

// A 1.8k-tet request with epsilon 1e-12: every edge splits every iteration, up to the server's
// tet budget (the 83 KB request grew to 25.6M tets and 1.8 GB before budgets existed).
Workload TinyEpsilon();

// Under AddressSanitizer freed memory sits in a quarantine of up to 256 MB and the shadow counts
// too, so a process's VmRSS grows with churn whatever leaks: the memory bounds are checked only
// without it (there LeakSanitizer checks the server at exit instead).
#if defined(__SANITIZE_ADDRESS__)
inline constexpr bool kMemoryIsMeaningful = false;
#else
inline constexpr bool kMemoryIsMeaningful = true;
#endif

// Core Refine of `w` with the options the server would use under `limits`.
RefineResult CoreResult(const Workload& w, const wire::ServiceLimits& limits = {});

// Empty when `actual` matches `expected` bit for bit in mesh, per-tet arrays, iterations and
// stop reason; otherwise what differs.
std::string ResultDifference(const RefineResult& expected, const RefineResult& actual);

}  // namespace tetrefine::hardening
