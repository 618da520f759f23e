#pragma once

// Who a call comes from, and whether it may call at all: bearer tokens, an allow-list of client
// certificate subjects, and the identity per-client quotas count by.

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "absl/strings/string_view.h"
#include "grpcpp/server_context.h"

namespace tetrefine::server {

// Bearer tokens and the identity each stands for, from a file of lines "<identity> <token>"
// ('#' starts a comment line; blank lines are skipped). Identities are [A-Za-z0-9._@-]+; a
// token is at least 16 printable characters without spaces and appears once. Several tokens
// may share an identity (rotation). Only SHA-256 digests of the tokens are kept.
class TokenTable {
 public:
  // Errors name the source and line (INVALID_ARGUMENT), or the unreadable file (NOT_FOUND).
  static absl::StatusOr<TokenTable> FromFile(const std::string& path);
  static absl::StatusOr<TokenTable> FromText(absl::string_view text, absl::string_view source);

  // The identity whose token `token` is. Every entry is compared, each in constant time (on
  // digests, so the token's length does not leak either): how long this takes does not depend
  // on which entry matches or how much of a wrong token is right.
  std::optional<std::string> Find(absl::string_view token) const;

  size_t size() const { return entries_.size(); }

 private:
  struct Entry {
    std::string identity;
    std::array<unsigned char, 32> digest;
  };
  std::vector<Entry> entries_;
};

// What a server asks of its callers. Default: nothing (identity = the peer's address).
struct AccessPolicy {
  std::optional<TokenTable> tokens;  // set: every Refine and GetServerInfo call needs a token
  // Non-empty: a client certificate's common name or full subject ("CN=a,O=b", its attributes
  // in any order) must be one of these (the server must require client certificates,
  // --tls_client_ca).
  std::vector<std::string> allowed_subjects;
  // --tls_client_ca: every Refine and GetServerInfo call must come with a verified client
  // certificate, also on the plaintext --local_listen (which then serves health checks only).
  bool require_client_certificate = false;
};

// The identity quotas count a call by: "token:<name>" when tokens are on, else "cert:<common
// name>" for a verified client certificate, else "peer:<address without port>". Errors:
// UNAUTHENTICATED for a missing or unknown token or a missing required certificate,
// PERMISSION_DENIED for a certificate subject not on the allow-list; each message says what the
// server expects.
absl::StatusOr<std::string> IdentifyCall(const AccessPolicy& policy,
                                         const grpc::ServerContextBase& context);

// The client a peer address stands for, for per-client quotas: "ipv4:10.0.0.7:51234" ->
// "10.0.0.7"; an IPv6 address counts by its /64, "ipv6:[2001:db8:1:2::7]:5000" ->
// "[2001:db8:1:2::]/64" (one host usually holds a whole /64), except loopback ("[::1]") and
// IPv4-mapped addresses ("ipv6:[::ffff:10.0.0.7]:5000" -> "10.0.0.7"); anything else unchanged.
std::string PeerAddress(absl::string_view peer);

}  // namespace tetrefine::server
