// A client in its own process, for tests that kill a client: refines the heavy workload on the
// server named by argv[1] and prints "iteration <n>" as each iteration's statistics arrive.

#include <cstdio>

#include "client/refine_client.h"
#include "tests/hardening/workloads.h"
#include "tests/support/server_process.h"

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: %s <host:port>\n", argv[0]);
    return 2;
  }
  const tetrefine::hardening::Workload& w = tetrefine::hardening::HeavyWorkload();
  tetrefine::client::RefineCallbacks callbacks;
  callbacks.on_iteration = [](const tetrefine::IterationStats& stats) {
    std::printf("iteration %d\n", stats.iteration);
    std::fflush(stdout);
  };
  std::printf("sending\n");
  std::fflush(stdout);
  const absl::StatusOr<tetrefine::client::ClientResult> result =
      tetrefine::client::RefineViaService(tetrefine::testing::NewUnsharedChannel(argv[1]), w.volume,
                                          w.mesh, w.options, callbacks);
  std::printf("finished: %s\n", result.status().ToString().c_str());
  return result.ok() ? 0 : 1;
}
