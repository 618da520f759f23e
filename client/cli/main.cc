// tetrefine: the command line. Everything but argument hand-over lives in tetrefine_cli.

#include <cstdio>
#include <cstdlib>
#include <new>
#include <string>
#include <vector>

#include "client/cli/commands.h"
#include "client/cli/exit_codes.h"
#include "client/io/temporary_files.h"
#include "grpc/support/log.h"
#include "spdlog/sinks/stdout_color_sinks.h"
#include "spdlog/spdlog.h"

namespace {

// gRPC core's own lines ("E1127 ... Handshake failed" before the CLI's one-line error, even under
// --quiet, in a sweep) say again what the CLI's message says: they go to spdlog's debug level.
// GRPC_VERBOSITY set in the environment keeps gRPC's logging as it is, for debugging.
void GrpcCoreLogToDebug(gpr_log_func_args* args) {
  spdlog::debug("grpc {}:{}: {}", args->file, args->line, args->message);
}

}  // namespace

int main(int argc, char** argv) {
  // Before any thread: a signal that ends a command mid-write removes its temporary files.
  tetrefine::io::RemoveTemporariesOnSignals();
  if (std::getenv("GRPC_VERBOSITY") == nullptr) gpr_set_log_function(GrpcCoreLogToDebug);
  // The embedded service logs through spdlog: keep its lines off stdout (which carries the
  // report) and drop the per-call access line it writes at info level.
  spdlog::set_default_logger(spdlog::stderr_color_mt("tetrefine"));
  spdlog::set_level(spdlog::level::warn);
  // A failed allocation in the command's own thread (reading, receiving, writing a large mesh)
  // is a message and exit 1, not an abort with a core dump (an outside review, 2026-11-29, under
  // `ulimit -v`); the embedded service turns one in a refinement into its call's error.
  try {
    return tetrefine::cli::RunTetrefine(std::vector<std::string>(argv, argv + argc));
  } catch (const std::bad_alloc&) {
    std::fputs(
        "tetrefine: out of memory: this process could not allocate more (see `ulimit -v` and "
        "the machine's memory); ask for less work (a larger --epsilon, a lower --max-tets)\n",
        stderr);
    return tetrefine::cli::kExitFailed;
  }
}
