// tetrefine: the command line. Everything but argument hand-over lives in tetrefine_cli.

#include <string>
#include <vector>

#include "client/cli/commands.h"
#include "spdlog/sinks/stdout_color_sinks.h"
#include "spdlog/spdlog.h"

int main(int argc, char** argv) {
  // The embedded service logs through spdlog: keep its lines off stdout (which carries the
  // report) and drop the per-call access line it writes at info level.
  spdlog::set_default_logger(spdlog::stderr_color_mt("tetrefine"));
  spdlog::set_level(spdlog::level::warn);
  return tetrefine::cli::RunTetrefine(std::vector<std::string>(argv, argv + argc));
}
