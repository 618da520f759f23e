#pragma once

#include <string>
#include <vector>

#include "client/cli/arg_parser.h"

namespace tetrefine::cli {

// The subcommands of `tetrefine`. Each takes the arguments after its name and returns the
// process exit code (see exit_codes.h).
struct Subcommand {
  const CommandSpec& (*spec)();
  int (*run)(const std::vector<std::string>& args);
};

const CommandSpec& RefineSpec();
int RunRefine(const std::vector<std::string>& args);

const CommandSpec& MeshSpec();
int RunMesh(const std::vector<std::string>& args);

const CommandSpec& VerifySpec();
int RunVerify(const std::vector<std::string>& args);

const CommandSpec& InfoSpec();
int RunInfo(const std::vector<std::string>& args);

const CommandSpec& HealthSpec();
int RunHealth(const std::vector<std::string>& args);

const CommandSpec& SliceSpec();
int RunSlice(const std::vector<std::string>& args);

const CommandSpec& PlotSpec();
int RunPlot(const std::vector<std::string>& args);

// All of the above, in the order `tetrefine --help` lists them.
const std::vector<Subcommand>& Subcommands();

// The whole program: dispatches argv[1] to a subcommand; `tetrefine --help` lists them.
int RunTetrefine(const std::vector<std::string>& argv);

}  // namespace tetrefine::cli
