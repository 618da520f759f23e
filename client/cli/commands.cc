#include "client/cli/commands.h"

#include <cstdio>
#include <string>

#include "absl/strings/str_cat.h"
#include "client/cli/exit_codes.h"

namespace tetrefine::cli {
namespace {

std::string ProgramHelp() {
  std::string text =
      "tetrefine: refine tetrahedral meshes immersed in voxel volumes until the mesh's linear\n"
      "interpolation matches the volume's trilinear one within a relative tolerance epsilon.\n\n"
      "Usage: tetrefine COMMAND [flags]      tetrefine COMMAND --help\n\nCommands:\n";
  for (const Subcommand& command : Subcommands()) {
    const CommandSpec& spec = command.spec();
    absl::StrAppend(&text, "  ", spec.name, std::string(8 - spec.name.size(), ' '), spec.summary,
                    "\n");
  }
  absl::StrAppend(&text,
                  "\nExamples:\n"
                  "  tetrefine refine --volume head.nii.gz --mesh head.vtu --epsilon 0.1\n"
                  "  tetrefine mesh --volume liver.nii --block 2 --mask-threshold 100 --output "
                  "liver.vtu\n"
                  "  tetrefine verify --volume head.nii.gz --mesh head.refined.vtu\n"
                  "  tetrefine health --server localhost:50051\n"
                  "  tetrefine slice --volume head.nii.gz --mesh head.vtu --mesh-after "
                  "head.refined.vtu --axis z --output slice.png\n"
                  "  tetrefine plot --stats-json default.json --stats-json paper.json --output "
                  "convergence.png\n"
                  "\nExit codes: 0 success, 1 failed (invalid mesh, not serving, service error),\n"
                  "2 bad flags or unusable input/output file (one line on stderr names it).\n"
                  "The gRPC server is a separate program: tetrefine_server --help.\n");
  return text;
}

}  // namespace

const std::vector<Subcommand>& Subcommands() {
  static const std::vector<Subcommand> commands = {
      {RefineSpec, RunRefine}, {MeshSpec, RunMesh},   {VerifySpec, RunVerify}, {InfoSpec, RunInfo},
      {HealthSpec, RunHealth}, {SliceSpec, RunSlice}, {PlotSpec, RunPlot},
  };
  return commands;
}

int RunTetrefine(const std::vector<std::string>& argv) {
  if (argv.size() < 2) {
    return Fail(
        "missing command: expected refine, mesh, verify, info, health, slice or plot (see "
        "tetrefine --help)",
        kExitUsage);
  }
  const std::string& name = argv[1];
  if (name == "-h" || name == "--help" || name == "help") {
    // "tetrefine help refine" reads naturally too.
    if (name == "help" && argv.size() > 2) {
      for (const Subcommand& command : Subcommands()) {
        if (command.spec().name == argv[2]) return command.run({"--help"});
      }
    }
    std::fputs(ProgramHelp().c_str(), stdout);
    return kExitOk;
  }
  if (name == "--version") {
    std::printf("tetrefine %s\n", TETREFINE_VERSION);
    return kExitOk;
  }
  for (const Subcommand& command : Subcommands()) {
    if (command.spec().name == name) {
      return command.run(std::vector<std::string>(argv.begin() + 2, argv.end()));
    }
  }
  return Fail(
      absl::StrCat(
          "unknown command '", name,
          "': expected refine, mesh, verify, info, health, slice or plot (see tetrefine --help)"),
      kExitUsage);
}

}  // namespace tetrefine::cli
