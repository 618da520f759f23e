// tetrefine health: grpc.health.v1 check of a tetrefine_server, for container HEALTHCHECKs and
// load balancer probes.

#include <chrono>
#include <cstdio>
#include <optional>

#include "absl/strings/str_cat.h"
#include "client/cli/command_support.h"
#include "client/cli/commands.h"
#include "client/cli/exit_codes.h"
#include "client/cli/grpc_channel.h"
#include "client/refine_client.h"

namespace tetrefine::cli {
namespace {

const char* StatusName(client::ServingStatus status) {
  switch (status) {
    case client::ServingStatus::kServing:
      return "SERVING";
    case client::ServingStatus::kNotServing:
      return "NOT_SERVING";
    case client::ServingStatus::kServiceUnknown:
      return "SERVICE_UNKNOWN";
    case client::ServingStatus::kUnknown:
      break;
  }
  return "UNKNOWN";
}

}  // namespace

const CommandSpec& HealthSpec() {
  static const CommandSpec* spec = [] {
    auto* s = new CommandSpec{
        .name = "health",
        .summary = "Ask a tetrefine_server whether it is serving (grpc.health.v1)",
        .usage = "tetrefine health --server HOST:PORT [--service NAME] [--timeout S] [TLS flags]",
        .description =
            "Prints the serving status. --service \"\" (the default) asks about the server as a\n"
            "whole; tetrefine.v1.Refiner about the refiner. A server that is draining after\n"
            "SIGTERM answers NOT_SERVING for tetrefine.v1.Refiner (a readiness probe) and stays\n"
            "SERVING for \"\" (a liveness probe must not kill it mid-drain).\n"
            "Exit: 0 SERVING, 1 anything else (not serving, unreachable, timed out), 2 bad flags.",
        .flags =
            {
                {"server", "HOST:PORT", "server address", true},
                {"service", "NAME", "service to ask about (default \"\": the whole server)"},
                {"timeout", "S", "seconds to wait for the answer (default 3)"},
            },
        .positional = ""};
    for (FlagSpec& flag : TlsFlagSpecs()) s->flags.push_back(std::move(flag));
    return s;
  }();
  return *spec;
}

int RunHealth(const std::vector<std::string>& args) {
  int exit_code = kExitOk;
  std::optional<ParsedArgs> parsed = ParseCommandLine(HealthSpec(), args, &exit_code);
  if (!parsed.has_value()) return exit_code;
  double timeout = 3.0;
  if (auto text = parsed->Get("timeout")) {
    absl::StatusOr<double> t = ParseFiniteDouble("timeout", *text);
    if (!t.ok()) return Fail(t.status(), kExitUsage);
    if (*t <= 0.0 || *t > 3600.0) {
      return Fail(absl::StrCat("--timeout: must be in (0, 3600] seconds, got '", *text, "'"),
                  kExitUsage);
    }
    timeout = *t;
  }
  const std::string server = *parsed->Get("server");
  const std::string service = parsed->Get("service").value_or("");
  absl::StatusOr<TlsFiles> tls = TlsFilesFromArgs(*parsed);
  if (!tls.ok()) return Fail(tls.status(), kExitUsage);
  absl::StatusOr<std::shared_ptr<grpc::Channel>> channel = MakeChannel(server, *tls);
  if (!channel.ok()) return Fail(channel.status(), kExitUsage);

  const auto deadline = std::chrono::system_clock::now() +
                        std::chrono::duration_cast<std::chrono::system_clock::duration>(
                            std::chrono::duration<double>(timeout));
  absl::StatusOr<client::ServingStatus> status = client::CheckHealth(*channel, service, deadline);
  if (!status.ok()) {
    const absl::Status failed = WithTlsHint(status.status(), *tls);
    return Fail(absl::StrCat("server ", server, ": ", absl::StatusCodeToString(failed.code()), ": ",
                             failed.message()),
                kExitFailed);
  }
  std::printf("%s\n", StatusName(*status));
  return *status == client::ServingStatus::kServing ? kExitOk : kExitFailed;
}

}  // namespace tetrefine::cli
