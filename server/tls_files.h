#pragma once

// The server's TLS files, checked before gRPC sees them: gRPC reports a PEM it cannot use only
// when it binds, as its own log lines and a bare "cannot listen", after the metrics endpoint has
// already failed on the same certificate.

#include <string>

#include "absl/status/status.h"

namespace tetrefine::server {

// The PEM texts of --tls_cert, --tls_key and --tls_client_ca (empty: not given) and their paths,
// for messages. INVALID_ARGUMENT naming the flag and the file when the certificate or the CA
// bundle holds no certificate, the key file no private key, or the key is not the certificate's.
absl::Status CheckServerTlsFiles(const std::string& cert_pem, const std::string& cert_path,
                                 const std::string& key_pem, const std::string& key_path,
                                 const std::string& ca_pem, const std::string& ca_path);

}  // namespace tetrefine::server
