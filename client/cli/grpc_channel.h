#pragma once

#include <memory>
#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "client/cli/arg_parser.h"
#include "grpcpp/channel.h"
#include "grpcpp/support/channel_arguments.h"

namespace tetrefine::cli {

// PEM files for a TLS connection to a tetrefine_server (started with --tls_cert/--tls_key, and
// --tls_client_ca for mutual TLS). Any of them set turns TLS on; without --tls-ca the system's
// root certificates verify the server.
struct TlsFiles {
  bool on = false;   // --tls: TLS with the system's root certificates (implied by the files)
  std::string ca;    // --tls-ca: CA bundle that signed the server's certificate
  std::string cert;  // --tls-cert: client certificate chain (mutual TLS)
  std::string key;   // --tls-key: private key of --tls-cert
  bool enabled() const { return on || !ca.empty() || !cert.empty() || !key.empty(); }
};

// A plaintext call's failure against a server that speaks TLS shows only as a closed socket:
// `status` with a hint to pass --tls (or --tls-ca) when that is what happened.
absl::Status WithTlsHint(const absl::Status& status, const TlsFiles& tls);

// The --tls, --tls-ca, --tls-cert and --tls-key flags, for a subcommand's spec.
std::vector<FlagSpec> TlsFlagSpecs();
// Their values; --tls-cert and --tls-key must come together.
absl::StatusOr<TlsFiles> TlsFilesFromArgs(const ParsedArgs& args);

// --token-file FILE: a bearer token for a server started with --token_file.
FlagSpec TokenFlagSpec();
// The token in --token-file (its first non-blank line, trimmed), or "" without the flag.
// Errors name the file: unreadable (NOT_FOUND), empty or holding spaces (INVALID_ARGUMENT).
absl::StatusOr<std::string> TokenFromArgs(const ParsedArgs& args);

// Checks the numeric port of each host:port in a gRPC target ("host:port", "[::1]:port",
// "dns:///host:port", "ipv4:a:p,b:p"): 1-65535. gRPC itself takes 70000 modulo 65536 and
// connects to port 4464, somebody else's. A host without a port (gRPC would dial port 0 or 443)
// is refused too; unix:/path and the like, and named ports, pass. The error names the target
// and the port.
absl::Status CheckTargetPorts(const std::string& address);

// The arguments of MakeChannel's channels: the receive limit and the keepalive pings.
grpc::ChannelArguments ChannelArgumentsForCli();

// A channel to `address` (host:port, or any gRPC target such as unix:/path), plain or TLS.
// Errors: a port out of range (CheckTargetPorts), an unreadable PEM file, named with its flag.
absl::StatusOr<std::shared_ptr<grpc::Channel>> MakeChannel(const std::string& address,
                                                           const TlsFiles& tls);

}  // namespace tetrefine::cli
