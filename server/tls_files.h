#pragma once

// The server's TLS files, checked before gRPC sees them: gRPC reports a PEM it cannot use only
// when it binds, as its own log lines and a bare "cannot listen", after the metrics endpoint has
// already failed on the same certificate.

#include <string>

#include "absl/status/status.h"

namespace tetrefine::server {

// One PEM file as a flag named it: its text, its path and the flag, for messages.
struct PemFile {
  std::string pem;
  std::string path;
  std::string flag;
};

// A certificate, its private key and a CA bundle (each may be absent: empty path).
// INVALID_ARGUMENT naming the flag and the file when the certificate or the CA bundle holds no
// certificate, the key file no private key, or the key is not the certificate's. The CLI checks
// its --tls-cert, --tls-key and --tls-ca with it too: gRPC's own word for a swapped or
// mismatched pair was "empty address list" (an outside review, 2026-11-28).
absl::Status CheckTlsFiles(const PemFile& cert, const PemFile& key, const PemFile& ca);

// CheckTlsFiles for --tls_cert, --tls_key and --tls_client_ca.
absl::Status CheckServerTlsFiles(const std::string& cert_pem, const std::string& cert_path,
                                 const std::string& key_pem, const std::string& key_path,
                                 const std::string& ca_pem, const std::string& ca_path);

}  // namespace tetrefine::server
