#pragma once

// How much memory the server may give its calls, and how much one call may need at worst.

#include <cstdint>
#include <optional>
#include <string>

namespace tetrefine::server {

// The memory limit of the cgroup this process runs in, bytes: cgroup v2 memory.max, else v1
// memory.limit_in_bytes, each looked up both at the cgroup root (a container's own view) and at
// this process's cgroup path from /proc/self/cgroup; the smallest limit found. nullopt when
// there is none ("max", or v1's "unlimited" of about 2^63). `root` replaces "/" for tests.
std::optional<int64_t> CgroupMemoryLimit(const std::string& root = "/");

// Physical memory of the machine, bytes.
int64_t PhysicalMemoryBytes();

// What the soft resource limits on address space leave this process, bytes: the smaller of
// RLIMIT_AS less the address space mapped now (VmSize) and RLIMIT_DATA less the data mapped now
// (VmData), never below 0; nullopt when neither is set. Why: `ulimit -v` is how batch systems
// and shared hosts bound a job's memory, and under it an allocation fails long before the
// machine or the cgroup runs out. Sized from physical memory alone, a server under
// `ulimit -v 2000000` offered 32 M-tet calls and the first large one ended the whole process on
// std::bad_alloc (outside review, 2026-11-29).
std::optional<int64_t> AddressSpaceLeft();

// The part of a memory limit the calls may reserve: the limit less what the process needs
// besides its calls (code, gRPC and TBB threads, allocator slack): max(256 MiB, 10% of it).
// Why: an idle tetrefine_server has 30-40 MB resident; the rest covers fragmentation, which
// grows with the number of calls. Never below 0.
int64_t BudgetForLimit(int64_t limit_bytes);

// Bytes the server reserves per tet of a call's output, by default. Measured peaks of
// tetrefine_server over one call, less its idle footprint: 78 bytes per output tet at 8.6 M and
// 82 at 1.08 M (tests/hardening/hardening_abuse_load_test.cc, which checks they stay below this),
// 85-92 for the core alone (docs/results/benchmarks.md), 131 when a 4.9 M-tet input is counted
// in (the T1 brain grid, deploy/kubernetes). The input is reserved apart, so 160 leaves the
// output about 1.7 times its measured need: room for allocator fragmentation when calls overlap.
inline constexpr int64_t kDefaultBytesPerOutputTet = 160;

// The most tets one iteration can make of one tet: the largest child count of the subdivision
// table (11: configuration 6's eight children, or a Schönhardt prism's Steiner fan).
int64_t MaxChildrenPerTet();

// The most tets a refinement of `input_tets` tets can end with: the tet budget, or fewer when
// `max_iterations` iterations cannot reach it (each multiplies the count by at most
// MaxChildrenPerTet()).
int64_t WorstCaseOutputTets(int64_t input_tets, int max_iterations, int64_t max_tets);

// What one open call may hold before its input is complete: up to one request message as gRPC
// received it plus its parsed copy.
inline int64_t OpenCallBytes(int64_t max_message_bytes) { return 2 * max_message_bytes; }

// "1.5 GiB", "312 MiB", "640 KiB", "12 B": for messages.
std::string HumanBytes(int64_t bytes);

}  // namespace tetrefine::server
