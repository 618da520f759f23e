#pragma once

// A minimal HTTPS server for one text document (Prometheus /metrics when gRPC uses TLS).
//
// Why not civetweb's TLS (which serves plain /metrics through prometheus-cpp): Debian 12's
// civetweb 1.15 loads OpenSSL by name at run time and calls SSL_get_peer_certificate, which
// OpenSSL 3 no longer exports; the first HTTPS connection then calls a null pointer and the
// server dies. This one links OpenSSL like gRPC does and serves GET <path> only.

#include <atomic>
#include <functional>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "absl/status/statusor.h"

namespace tetrefine::server {

class HttpsEndpoint {
 public:
  // Serves GET `path` on `address` (host:port, port 0: any) with the PEM certificate chain and
  // key, answering each request with `body()` as text/plain. `workers` connections are served
  // at once; one whose request has not arrived whole within `request_timeout_ms` is dropped, so
  // a few clients that never finish a request cannot keep a scrape out for long.
  // UNAVAILABLE (naming the address or file) when it cannot listen or load the certificate.
  static absl::StatusOr<std::unique_ptr<HttpsEndpoint>> Start(
      const std::string& address, const std::string& cert_file, const std::string& key_file,
      std::string path, std::function<std::string()> body, int workers = 4,
      int request_timeout_ms = 5000);
  // Stops accepting and joins the workers (each ends within request_timeout_ms).
  ~HttpsEndpoint();
  HttpsEndpoint(const HttpsEndpoint&) = delete;
  HttpsEndpoint& operator=(const HttpsEndpoint&) = delete;

  int port() const { return port_; }

 private:
  HttpsEndpoint() = default;
  void Serve();
  void Handle(int fd);

  void* ctx_ = nullptr;  // SSL_CTX*
  int listen_fd_ = -1;
  int port_ = 0;
  std::string path_;
  std::function<std::string()> body_;
  int request_timeout_ms_ = 5000;
  std::atomic<bool> stopping_{false};
  std::vector<std::thread> workers_;
};

}  // namespace tetrefine::server
