#include "client/cli/grpc_channel.h"

#include <algorithm>

#include "absl/strings/ascii.h"
#include "absl/strings/match.h"
#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_split.h"
#include "absl/strings/strip.h"
#include "client/io/file_bytes.h"
#include "grpcpp/create_channel.h"
#include "grpcpp/security/credentials.h"
#include "server/tls_files.h"

namespace tetrefine::cli {
namespace {

absl::StatusOr<std::string> ReadPem(const std::string& path, const char* flag) {
  if (path.empty()) return std::string();
  absl::StatusOr<std::string> pem = io::ReadFileBytes(path);
  if (!pem.ok()) {
    return absl::Status(pem.status().code(), absl::StrCat(pem.status().message(), " (", flag, ")"));
  }
  if (pem->find("-----BEGIN") == std::string::npos) {
    return absl::InvalidArgumentError(absl::StrCat(path, ": not a PEM file (", flag, ")"));
  }
  return pem;
}

}  // namespace

std::vector<FlagSpec> TlsFlagSpecs() {
  return {
      {"tls", "", "TLS, verifying the server with the system's root certificates"},
      {"tls-ca", "FILE", "TLS: PEM CA bundle that verifies the server (instead of the system's)"},
      {"tls-cert", "FILE", "TLS: PEM client certificate, for servers that require one"},
      {"tls-key", "FILE", "TLS: PEM private key of --tls-cert"},
  };
}

absl::StatusOr<TlsFiles> TlsFilesFromArgs(const ParsedArgs& args) {
  TlsFiles tls;
  tls.on = args.Has("tls");
  tls.ca = args.Get("tls-ca").value_or("");
  tls.cert = args.Get("tls-cert").value_or("");
  tls.key = args.Get("tls-key").value_or("");
  if (tls.cert.empty() != tls.key.empty()) {
    return absl::InvalidArgumentError("--tls-cert and --tls-key go together");
  }
  return tls;
}

absl::Status WithTlsHint(const absl::Status& status, const TlsFiles& tls) {
  if (tls.enabled() || !absl::IsUnavailable(status) ||
      !absl::StrContains(status.message(), "Socket closed")) {
    return status;
  }
  return absl::Status(status.code(),
                      absl::StrCat(status.message(),
                                   " (a server that uses TLS closes plaintext connections: pass "
                                   "--tls, or --tls-ca with its CA)"));
}

FlagSpec TokenFlagSpec() {
  return {"token-file", "FILE",
          "bearer token for a server started with --token_file (the file's first line)"};
}

absl::StatusOr<std::string> TokenFromArgs(const ParsedArgs& args) {
  const std::optional<std::string> path = args.Get("token-file");
  if (!path.has_value()) return std::string();
  absl::StatusOr<std::string> text = io::ReadFileBytes(*path);
  if (!text.ok()) {
    return absl::Status(text.status().code(),
                        absl::StrCat(text.status().message(), " (--token-file)"));
  }
  for (absl::string_view line : absl::StrSplit(*text, '\n')) {
    line = absl::StripAsciiWhitespace(line);
    if (line.empty()) continue;
    if (line.find_first_of(" \t") != absl::string_view::npos) {
      return absl::InvalidArgumentError(
          absl::StrCat(*path, ": the token must be one word on the first line (--token-file)"));
    }
    return std::string(line);
  }
  return absl::InvalidArgumentError(absl::StrCat(*path, ": no token in it (--token-file)"));
}

absl::Status CheckTargetPorts(const std::string& address) {
  absl::string_view rest = address;
  // Only the resolvers that take host:port lists; unix:, vsock: and the like have no port.
  bool list = false;
  // A web address is not a gRPC target: gRPC took "http://host:port" for a host name, and the
  // run failed with a DNS error, exit 1 (an outside review).
  for (absl::string_view scheme : {"http://", "https://", "grpc://", "grpcs://"}) {
    if (absl::StartsWithIgnoreCase(rest, scheme)) {
      return absl::InvalidArgumentError(absl::StrCat("--server: '", address,
                                                     "' is a URL; write host:port without ", scheme,
                                                     " (--tls for an encrypted connection)"));
    }
  }
  if (absl::ConsumePrefix(&rest, "dns:")) {
    if (absl::ConsumePrefix(&rest, "//")) {  // dns://authority/host:port
      const size_t slash = rest.find('/');
      rest = slash == absl::string_view::npos ? absl::string_view() : rest.substr(slash + 1);
    }
  } else if (absl::ConsumePrefix(&rest, "ipv4:") || absl::ConsumePrefix(&rest, "ipv6:")) {
    list = true;
  } else if (rest.find("://") != absl::string_view::npos || absl::StartsWith(rest, "unix:") ||
             absl::StartsWith(rest, "unix-abstract:") || absl::StartsWith(rest, "vsock:")) {
    return absl::OkStatus();
  }
  const std::vector<absl::string_view> host_ports =
      list ? absl::StrSplit(rest, ',') : std::vector<absl::string_view>{rest};
  for (absl::string_view host_port : host_ports) {
    absl::string_view port;
    // A host without a port dialled port 0 ("Connection refused", exit 1) where a sweep expected
    // a flag error; a bare IPv6 address (two colons or more) cannot say where its port starts.
    const auto no_port = [&] {
      return absl::InvalidArgumentError(absl::StrCat(
          "--server: '", host_port,
          host_port == address ? std::string() : absl::StrCat("' of '", address),
          "' has no port: write host:port ([address]:port for IPv6); tetrefine_server listens "
          "on port 50051 unless told otherwise"));
    };
    if (absl::StartsWith(host_port, "[")) {
      const size_t close = host_port.find("]:");
      if (close == absl::string_view::npos) return no_port();
      port = host_port.substr(close + 2);
    } else {
      const size_t colon = host_port.find(':');
      if (colon == absl::string_view::npos || host_port.find(':', colon + 1) != host_port.npos) {
        return no_port();
      }
      port = host_port.substr(colon + 1);
    }
    if (port.empty()) return no_port();
    if (port.empty() || !std::all_of(port.begin(), port.end(), absl::ascii_isdigit)) continue;
    int number = 0;
    if (port.size() > 5 || !absl::SimpleAtoi(port, &number) || number < 1 || number > 65535) {
      return absl::InvalidArgumentError(
          absl::StrCat("--server: port ", port, " of '", address, "' is out of range (1-65535)"));
    }
  }
  return absl::OkStatus();
}

grpc::ChannelArguments ChannelArgumentsForCli() {
  grpc::ChannelArguments args;
  // Response chunks are at most 3 MiB, so the default 4 MiB receive limit suffices; say so
  // explicitly rather than depend on the default.
  args.SetMaxReceiveMessageSize(8 << 20);
  // A long refinement can be silent for minutes (the final lattice check); keepalive pings keep
  // NATs and load balancers from dropping the connection meanwhile. tetrefine_server accepts
  // pings every 10 s (--keepalive_seconds documents its side).
  args.SetInt(GRPC_ARG_KEEPALIVE_TIME_MS, 30'000);
  args.SetInt(GRPC_ARG_KEEPALIVE_TIMEOUT_MS, 20'000);
  // And without a limit: gRPC's default sends at most two pings while no data flows, so a call
  // silent for a minute (a queue wait, a long iteration, the final lattice check) and then a
  // frozen server left the CLI waiting for ever (an outside review, 2026-11-29: still waiting
  // 260 s after the freeze). Every 30 s suits the server's policy (a ping every 10 s at most).
  args.SetInt(GRPC_ARG_HTTP2_MAX_PINGS_WITHOUT_DATA, 0);
  return args;
}

absl::StatusOr<std::shared_ptr<grpc::Channel>> MakeChannel(const std::string& address,
                                                           const TlsFiles& tls) {
  if (address.empty()) return absl::InvalidArgumentError("--server: empty address");
  if (absl::Status ports = CheckTargetPorts(address); !ports.ok()) return ports;
  const grpc::ChannelArguments args = ChannelArgumentsForCli();
  if (!tls.enabled()) {
    return grpc::CreateCustomChannel(address, grpc::InsecureChannelCredentials(), args);
  }
  grpc::SslCredentialsOptions options;
  absl::StatusOr<std::string> ca = ReadPem(tls.ca, "--tls-ca");
  if (!ca.ok()) return ca.status();
  absl::StatusOr<std::string> cert = ReadPem(tls.cert, "--tls-cert");
  if (!cert.ok()) return cert.status();
  absl::StatusOr<std::string> key = ReadPem(tls.key, "--tls-key");
  if (!key.ok()) return key.status();
  // gRPC's word for a swapped or mismatched pair, or a key given as the CA, was "empty address
  // list": the files are checked here, naming the flag and the file.
  if (absl::Status files = server::CheckTlsFiles(
          {*cert, tls.cert, "--tls-cert"}, {*key, tls.key, "--tls-key"}, {*ca, tls.ca, "--tls-ca"});
      !files.ok()) {
    return files;
  }
  options.pem_root_certs = *ca;
  options.pem_cert_chain = *cert;
  options.pem_private_key = *key;
  return grpc::CreateCustomChannel(address, grpc::SslCredentials(options), args);
}

}  // namespace tetrefine::cli
