// Peak memory of one Refine call on the ripple workload, measured in this fresh process: the
// input is built first, then the kernel's resident high-water mark (VmHWM) is reset and Refine
// runs. Prints one JSON object: the RSS before the call, the peak added during it, and that peak
// per output tet (it includes the returned mesh and every temporary).
// Run: build/bench/peak_memory --cells=58 --threads=1
#include <cstdio>
#include <string>

#include "absl/flags/flag.h"
#include "absl/flags/parse.h"
#include "absl/flags/usage.h"
#include "absl/flags/usage_config.h"
#include "absl/strings/match.h"
#include "bench/support/process_memory.h"
#include "bench/support/ripple_workload.h"
#include "core/refine.h"

ABSL_FLAG(int, cells, 58, "cells per axis of the structured mesh (5 tets per cell)");
ABSL_FLAG(int, threads, 1, "RefineOptions::threads (0: all cores)");
ABSL_FLAG(int, max_iterations, 1, "RefineOptions::max_iterations");

int main(int argc, char** argv) {
  absl::SetProgramUsageMessage(
      "Peak memory of one Refine call on the ripple workload, as one JSON object.\n"
      "Usage: peak_memory [--cells=N] [--threads=N] [--max_iterations=N]");
  // --help lists this file's flags (Abseil's default looks for files named after the program).
  absl::FlagsUsageConfig usage;
  usage.contains_help_flags = [](absl::string_view file) {
    return absl::EndsWith(file, "bench/peak_memory_main.cc");
  };
  usage.contains_helpshort_flags = usage.contains_help_flags;
  absl::SetFlagsUsageConfig(usage);
  absl::ParseCommandLine(argc, argv);
  using namespace tetrefine;  // NOLINT(build/namespaces): a tiny tool
  const int cells = absl::GetFlag(FLAGS_cells);
  if (cells < 1 || cells > 400) {
    std::fprintf(stderr, "--cells must be in [1, 400]\n");
    return 2;
  }
  const bench::RippleWorkload w = bench::MakeRippleWorkload(cells);
  RefineOptions o;
  o.epsilon = bench::kRippleEpsilon;
  o.max_iterations = absl::GetFlag(FLAGS_max_iterations);
  o.lattice_n = 0;
  o.threads = absl::GetFlag(FLAGS_threads);
  int64_t out = 0, added = 0;
  double seconds = 0.0;
  int64_t rss_before = -1;
  {
    bench::PeakMemoryScope scope;
    rss_before = scope.start_rss_bytes();
    absl::StatusOr<RefineResult> r = Refine(w.volume, w.mesh, o);
    if (!r.ok()) {
      std::fprintf(stderr, "Refine: %s\n", std::string(r.status().message()).c_str());
      return 1;
    }
    out = static_cast<int64_t>(r->mesh.tets.size());
    seconds = r->seconds;
    added = scope.AddedPeakBytes();  // while the result is still alive
  }
  std::printf(
      "{\"cells\": %d, \"threads\": %d, \"max_iterations\": %d, \"tets_in\": %zu, "
      "\"tets_out\": %lld, \"seconds\": %.6f, \"rss_before_bytes\": %lld, "
      "\"peak_added_bytes\": %lld, \"peak_bytes_per_output_tet\": %.2f}\n",
      cells, o.threads, o.max_iterations, w.mesh.tets.size(), static_cast<long long>(out), seconds,
      static_cast<long long>(rss_before), static_cast<long long>(added),
      added < 0 || out == 0 ? -1.0 : static_cast<double>(added) / static_cast<double>(out));
  return added < 0 ? 1 : 0;
}
