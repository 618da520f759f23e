#include "server/https_endpoint.h"

#include <fcntl.h>
#include <netdb.h>
#include <openssl/err.h>
#include <openssl/ssl.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <chrono>
#include <cstring>
#include <utility>

#include "absl/strings/str_cat.h"

namespace tetrefine::server {
namespace {

using Clock = std::chrono::steady_clock;

// A request line and headers larger than this are not a scrape.
constexpr size_t kMaxRequestBytes = 8192;

std::string OpenSslError() {
  const unsigned long code = ERR_get_error();
  if (code == 0) return "unknown error";
  char text[256];
  ERR_error_string_n(code, text, sizeof(text));
  return text;
}

int RemainingMs(Clock::time_point deadline) {
  const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now());
  return static_cast<int>(std::max<int64_t>(0, left.count()));
}

// Runs one non-blocking OpenSSL operation to completion, waiting for the socket as it asks,
// until `deadline`. Its result (> 0 done), or -1.
template <typename Op>
int Drive(SSL* ssl, int fd, Clock::time_point deadline, Op op) {
  for (;;) {
    const int result = op();
    if (result > 0) return result;
    const int error = SSL_get_error(ssl, result);
    pollfd p{fd, 0, 0};
    if (error == SSL_ERROR_WANT_READ) {
      p.events = POLLIN;
    } else if (error == SSL_ERROR_WANT_WRITE) {
      p.events = POLLOUT;
    } else {
      return -1;
    }
    const int wait = RemainingMs(deadline);
    if (wait == 0 || poll(&p, 1, wait) <= 0) return -1;
  }
}

}  // namespace

absl::StatusOr<std::unique_ptr<HttpsEndpoint>> HttpsEndpoint::Start(
    const std::string& address, const std::string& cert_file, const std::string& key_file,
    std::string path, std::function<std::string()> body, int workers, int request_timeout_ms) {
  std::unique_ptr<HttpsEndpoint> endpoint(new HttpsEndpoint());
  endpoint->path_ = std::move(path);
  endpoint->body_ = std::move(body);
  endpoint->request_timeout_ms_ = request_timeout_ms;

  SSL_CTX* ctx = SSL_CTX_new(TLS_server_method());
  if (ctx == nullptr) return absl::UnavailableError("cannot create a TLS context");
  endpoint->ctx_ = ctx;
  SSL_CTX_set_min_proto_version(ctx, TLS1_2_VERSION);
  if (SSL_CTX_use_certificate_chain_file(ctx, cert_file.c_str()) != 1) {
    return absl::UnavailableError(
        absl::StrCat("cannot load the certificate ", cert_file, ": ", OpenSslError()));
  }
  if (SSL_CTX_use_PrivateKey_file(ctx, key_file.c_str(), SSL_FILETYPE_PEM) != 1 ||
      SSL_CTX_check_private_key(ctx) != 1) {
    return absl::UnavailableError(
        absl::StrCat("cannot load the key ", key_file, ": ", OpenSslError()));
  }

  const size_t colon = address.rfind(':');
  if (colon == std::string::npos) {
    return absl::UnavailableError(absl::StrCat(address, ": expected host:port"));
  }
  std::string host = address.substr(0, colon);
  if (host.size() >= 2 && host.front() == '[' && host.back() == ']') {
    host = host.substr(1, host.size() - 2);
  }
  const std::string port = address.substr(colon + 1);
  addrinfo hints{};
  hints.ai_family = AF_UNSPEC;
  hints.ai_socktype = SOCK_STREAM;
  hints.ai_flags = AI_PASSIVE;
  addrinfo* found = nullptr;
  if (getaddrinfo(host.empty() ? nullptr : host.c_str(), port.c_str(), &hints, &found) != 0 ||
      found == nullptr) {
    return absl::UnavailableError(absl::StrCat("cannot resolve ", address));
  }
  const int fd = socket(found->ai_family, found->ai_socktype | SOCK_CLOEXEC, found->ai_protocol);
  const int yes = 1;
  if (fd >= 0) setsockopt(fd, SOL_SOCKET, SO_REUSEADDR, &yes, sizeof(yes));
  const bool bound =
      fd >= 0 && bind(fd, found->ai_addr, found->ai_addrlen) == 0 && listen(fd, 64) == 0;
  freeaddrinfo(found);
  if (!bound) {
    const std::string why = std::strerror(errno);
    if (fd >= 0) close(fd);
    return absl::UnavailableError(absl::StrCat("cannot listen on ", address, ": ", why));
  }
  endpoint->listen_fd_ = fd;
  sockaddr_storage bound_address{};
  socklen_t length = sizeof(bound_address);
  getsockname(fd, reinterpret_cast<sockaddr*>(&bound_address), &length);
  endpoint->port_ = ntohs(bound_address.ss_family == AF_INET6
                              ? reinterpret_cast<sockaddr_in6*>(&bound_address)->sin6_port
                              : reinterpret_cast<sockaddr_in*>(&bound_address)->sin_port);
  for (int i = 0; i < workers; ++i) {
    endpoint->workers_.emplace_back([raw = endpoint.get()] { raw->Serve(); });
  }
  return endpoint;
}

HttpsEndpoint::~HttpsEndpoint() {
  stopping_.store(true);
  if (listen_fd_ >= 0) shutdown(listen_fd_, SHUT_RDWR);  // wakes the workers' accept
  for (std::thread& worker : workers_) worker.join();
  if (listen_fd_ >= 0) close(listen_fd_);
  if (ctx_ != nullptr) SSL_CTX_free(static_cast<SSL_CTX*>(ctx_));
}

void HttpsEndpoint::Serve() {
  while (!stopping_.load()) {
    const int fd = accept4(listen_fd_, nullptr, nullptr, SOCK_CLOEXEC | SOCK_NONBLOCK);
    if (fd < 0) {
      if (errno == EINTR || errno == ECONNABORTED || errno == EMFILE || errno == ENFILE) {
        if (errno == EMFILE || errno == ENFILE)
          std::this_thread::sleep_for(std::chrono::milliseconds(50));
        continue;
      }
      return;  // the listener was shut down
    }
    Handle(fd);
    close(fd);
  }
}

void HttpsEndpoint::Handle(int fd) {
  SSL* ssl = SSL_new(static_cast<SSL_CTX*>(ctx_));
  if (ssl == nullptr) return;
  SSL_set_fd(ssl, fd);
  // One deadline for the handshake and the whole request; another for writing the answer.
  const Clock::time_point deadline = Clock::now() + std::chrono::milliseconds(request_timeout_ms_);
  std::string request;
  bool complete = false;
  if (Drive(ssl, fd, deadline, [&] { return SSL_accept(ssl); }) > 0) {
    char buffer[1024];
    while (!complete && request.size() < kMaxRequestBytes) {
      const int n = Drive(ssl, fd, deadline, [&] { return SSL_read(ssl, buffer, sizeof(buffer)); });
      if (n <= 0) break;
      request.append(buffer, static_cast<size_t>(n));
      complete = request.find("\r\n\r\n") != std::string::npos;
    }
  }
  if (complete) {
    // "GET /metrics HTTP/1.1": the path up to a query string.
    std::string status = "404 Not Found", content;
    if (request.rfind("GET ", 0) != 0) {
      status = "405 Method Not Allowed";
    } else {
      const size_t end = request.find_first_of(" ?", 4);
      if (end != std::string::npos && request.compare(4, end - 4, path_) == 0) {
        status = "200 OK";
        content = body_();
      }
    }
    const std::string response =
        absl::StrCat("HTTP/1.1 ", status,
                     "\r\nContent-Type: text/plain; version=0.0.4; charset=utf-8\r\n"
                     "Content-Length: ",
                     content.size(), "\r\nConnection: close\r\n\r\n", content);
    const Clock::time_point write_deadline =
        Clock::now() + std::chrono::milliseconds(request_timeout_ms_);
    size_t sent = 0;
    while (sent < response.size()) {
      const int n = Drive(ssl, fd, write_deadline, [&] {
        return SSL_write(ssl, response.data() + sent, static_cast<int>(response.size() - sent));
      });
      if (n <= 0) break;
      sent += static_cast<size_t>(n);
    }
    SSL_shutdown(ssl);
  }
  SSL_free(ssl);
}

}  // namespace tetrefine::server
