#include "client/cli/grpc_channel.h"

#include "absl/strings/str_cat.h"
#include "client/io/file_bytes.h"
#include "grpcpp/create_channel.h"
#include "grpcpp/security/credentials.h"

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
      {"tls-ca", "FILE", "TLS: PEM CA bundle that verifies the server (default: system roots)"},
      {"tls-cert", "FILE", "TLS: PEM client certificate, for servers that require one"},
      {"tls-key", "FILE", "TLS: PEM private key of --tls-cert"},
  };
}

absl::StatusOr<TlsFiles> TlsFilesFromArgs(const ParsedArgs& args) {
  TlsFiles tls;
  tls.ca = args.Get("tls-ca").value_or("");
  tls.cert = args.Get("tls-cert").value_or("");
  tls.key = args.Get("tls-key").value_or("");
  if (tls.cert.empty() != tls.key.empty()) {
    return absl::InvalidArgumentError("--tls-cert and --tls-key go together");
  }
  return tls;
}

absl::StatusOr<std::shared_ptr<grpc::Channel>> MakeChannel(const std::string& address,
                                                           const TlsFiles& tls) {
  if (address.empty()) return absl::InvalidArgumentError("--server: empty address");
  grpc::ChannelArguments args;
  // Response chunks are at most 3 MiB, so the default 4 MiB receive limit suffices; say so
  // explicitly rather than depend on the default.
  args.SetMaxReceiveMessageSize(8 << 20);
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
  options.pem_root_certs = *ca;
  options.pem_cert_chain = *cert;
  options.pem_private_key = *key;
  return grpc::CreateCustomChannel(address, grpc::SslCredentials(options), args);
}

}  // namespace tetrefine::cli
