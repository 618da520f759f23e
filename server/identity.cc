#include "server/identity.h"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <openssl/crypto.h>
#include <openssl/sha.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "absl/strings/ascii.h"
#include "absl/strings/match.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_join.h"
#include "absl/strings/str_split.h"
#include "absl/strings/strip.h"
#include "grpc/grpc_security_constants.h"

namespace tetrefine::server {
namespace {

// 16 characters of any token generator (hex, base64) carry 64 bits or more.
constexpr size_t kMinTokenLength = 16;

std::array<unsigned char, 32> Digest(absl::string_view text) {
  std::array<unsigned char, 32> digest;
  SHA256(reinterpret_cast<const unsigned char*>(text.data()), text.size(), digest.data());
  return digest;
}

bool ValidIdentity(absl::string_view name) {
  if (name.empty()) return false;
  for (char c : name) {
    if (!absl::ascii_isalnum(static_cast<unsigned char>(c)) && c != '.' && c != '_' && c != '@' &&
        c != '-') {
      return false;
    }
  }
  return true;
}

std::vector<std::string> Property(const grpc::AuthContext& auth, const char* name) {
  std::vector<std::string> values;
  for (const grpc::string_ref& value : auth.FindPropertyValues(name)) {
    values.emplace_back(value.data(), value.size());
  }
  return values;
}

// A subject's attributes in a canonical order: gRPC prints "O=acme,CN=alice" for the subject an
// operator writes as "CN=alice,O=acme" (an operator sweep followed the help's example and was
// refused). Attributes are split at commas that are not escaped ("\\,"), trimmed and sorted.
std::string CanonicalSubject(absl::string_view subject) {
  std::vector<std::string> parts;
  std::string part;
  for (size_t i = 0; i < subject.size(); ++i) {
    if (subject[i] == '\\' && i + 1 < subject.size()) {
      part.append(subject.data() + i, 2);
      ++i;
    } else if (subject[i] == ',') {
      parts.emplace_back(absl::StripAsciiWhitespace(part));
      part.clear();
    } else {
      part += subject[i];
    }
  }
  parts.emplace_back(absl::StripAsciiWhitespace(part));
  std::sort(parts.begin(), parts.end());
  return absl::StrJoin(parts, ",");
}

}  // namespace

absl::StatusOr<TokenTable> TokenTable::FromFile(const std::string& path) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) {
    return absl::InvalidArgumentError(absl::StrCat(path, ": is a directory, not a token file"));
  }
  std::ifstream in(path, std::ios::binary);
  if (!in) return absl::NotFoundError(absl::StrCat(path, ": cannot read the token file"));
  std::ostringstream text;
  text << in.rdbuf();
  return FromText(text.str(), path);
}

absl::StatusOr<TokenTable> TokenTable::FromText(absl::string_view text, absl::string_view source) {
  TokenTable table;
  int line_number = 0;
  for (absl::string_view line : absl::StrSplit(text, '\n')) {
    ++line_number;
    line = absl::StripAsciiWhitespace(line);
    if (line.empty() || line.front() == '#') continue;
    const std::vector<absl::string_view> fields =
        absl::StrSplit(line, absl::ByAnyChar(" \t"), absl::SkipEmpty());
    auto error = [&](absl::string_view what) {
      return absl::InvalidArgumentError(absl::StrCat(source, ":", line_number, ": ", what));
    };
    if (fields.size() != 2) return error("expected \"<identity> <token>\"");
    if (!ValidIdentity(fields[0])) {
      return error(absl::StrCat("identity '", fields[0], "' must be [A-Za-z0-9._@-]+"));
    }
    if (fields[1].size() < kMinTokenLength) {
      return error(absl::StrCat("the token of ", fields[0], " has ", fields[1].size(),
                                " characters; at least ", kMinTokenLength, " are needed"));
    }
    Entry entry{.identity = std::string(fields[0]), .digest = Digest(fields[1])};
    for (const Entry& other : table.entries_) {
      if (other.digest == entry.digest) {
        return error(absl::StrCat("the token of ", entry.identity, " is already the token of ",
                                  other.identity));
      }
    }
    table.entries_.push_back(std::move(entry));
  }
  if (table.entries_.empty()) {
    return absl::InvalidArgumentError(absl::StrCat(source, ": no tokens"));
  }
  return table;
}

std::optional<std::string> TokenTable::Find(absl::string_view token) const {
  const std::array<unsigned char, 32> digest = Digest(token);
  const Entry* match = nullptr;
  for (const Entry& entry : entries_) {
    // No early exit: every entry costs the same.
    const bool same = CRYPTO_memcmp(entry.digest.data(), digest.data(), digest.size()) == 0;
    match = same ? &entry : match;
  }
  if (match == nullptr) return std::nullopt;
  return match->identity;
}

namespace {

// An IPv6 address as the client it stands for: one host usually holds a whole /64 (SLAAC,
// privacy addresses), so per-address quotas count the /64 ("[2001:db8:1:2::]/64"); an
// IPv4-mapped address is its IPv4 one, and loopback stays "[::1]". Unparsable text is kept.
// Found by a service sweep: quotas per address are only as good as the cost of a new address,
// and a /64 holds 2^64 of them.
std::string Ipv6Client(absl::string_view bracketed) {
  absl::string_view text = bracketed;
  if (!absl::ConsumePrefix(&text, "[") || !absl::ConsumeSuffix(&text, "]")) {
    return std::string(bracketed);
  }
  const std::string host(text.substr(0, text.find('%')));  // no zone id
  in6_addr address{};
  if (inet_pton(AF_INET6, host.c_str(), &address) != 1) return std::string(bracketed);
  if (IN6_IS_ADDR_V4MAPPED(&address)) {
    char v4[INET_ADDRSTRLEN];
    if (inet_ntop(AF_INET, &address.s6_addr[12], v4, sizeof(v4)) != nullptr) return v4;
    return std::string(bracketed);
  }
  if (IN6_IS_ADDR_LOOPBACK(&address)) return std::string(bracketed);
  std::fill(address.s6_addr + 8, address.s6_addr + 16, 0);
  char prefix[INET6_ADDRSTRLEN];
  if (inet_ntop(AF_INET6, &address, prefix, sizeof(prefix)) == nullptr) {
    return std::string(bracketed);
  }
  return absl::StrCat("[", prefix, "]/64");
}

}  // namespace

std::string PeerAddress(absl::string_view peer) {
  absl::string_view address = peer;
  const bool ipv6 = absl::ConsumePrefix(&address, "ipv6:");
  if (!ipv6 && !absl::ConsumePrefix(&address, "ipv4:")) return std::string(peer);
  const size_t colon = address.rfind(':');
  const size_t bracket = address.rfind(']');
  if (colon != absl::string_view::npos && (bracket == absl::string_view::npos || colon > bracket)) {
    address = address.substr(0, colon);
  }
  return ipv6 ? Ipv6Client(address) : std::string(address);
}

absl::StatusOr<std::string> IdentifyCall(const AccessPolicy& policy,
                                         const grpc::ServerContextBase& context) {
  const std::shared_ptr<const grpc::AuthContext> auth = context.auth_context();
  std::vector<std::string> common_names, subjects;
  if (auth != nullptr && auth->IsPeerAuthenticated()) {
    common_names = Property(*auth, GRPC_X509_CN_PROPERTY_NAME);
    subjects = Property(*auth, GRPC_X509_SUBJECT_PROPERTY_NAME);
  }
  if (policy.require_client_certificate && common_names.empty() && subjects.empty()) {
    // The plaintext --local_listen has no certificates: it let any local process refine
    // without one (found by an operator sweep; in Kubernetes every container of the pod shares
    // that loopback).
    return absl::UnauthenticatedError(
        "this server requires a client certificate (--tls_client_ca): call its TLS listener "
        "with one; the plaintext --local_listen serves health checks only");
  }
  if (!policy.allowed_subjects.empty()) {
    std::vector<std::string> canonical;
    for (const std::string& subject : subjects) canonical.push_back(CanonicalSubject(subject));
    bool allowed = false;
    for (const std::string& entry : policy.allowed_subjects) {
      const std::string entry_canonical = CanonicalSubject(entry);
      for (const std::string& name : common_names) allowed = allowed || name == entry;
      for (const std::string& subject : canonical) allowed = allowed || subject == entry_canonical;
    }
    if (!allowed) {
      return absl::PermissionDeniedError(absl::StrCat(
          "client certificate ",
          subjects.empty() ? std::string("(none)") : absl::StrCat("'", subjects.front(), "'"),
          " is not on this server's allow-list (--tls_allowed_subjects)"));
    }
  }
  if (policy.tokens.has_value()) {
    const auto& metadata = context.client_metadata();
    const auto header = metadata.find("authorization");
    if (header == metadata.end()) {
      return absl::UnauthenticatedError(
          "this server requires a bearer token: send call metadata 'authorization: Bearer "
          "<token>' (tetrefine CLI: --token-file)");
    }
    absl::string_view value(header->second.data(), header->second.size());
    // The scheme's case does not matter (RFC 7235 section 2.1): proxies and HTTP clients
    // that write "bearer" were refused (an outside review, 2026-11-29).
    if (!absl::StartsWithIgnoreCase(value, "Bearer ")) {
      return absl::UnauthenticatedError("authorization metadata must be 'Bearer <token>'");
    }
    value.remove_prefix(7);
    std::optional<std::string> identity = policy.tokens->Find(absl::StripAsciiWhitespace(value));
    if (!identity.has_value()) {
      return absl::UnauthenticatedError("the bearer token is not one this server knows");
    }
    return absl::StrCat("token:", *identity);
  }
  if (!common_names.empty()) return absl::StrCat("cert:", common_names.front());
  return absl::StrCat("peer:", PeerAddress(context.peer()));
}

}  // namespace tetrefine::server
