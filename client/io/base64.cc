#include "client/io/base64.h"

#include <array>

#include "absl/status/status.h"
#include "absl/strings/escaping.h"
#include "absl/strings/str_cat.h"

namespace tetrefine::io {
namespace {

constexpr int kPad = 64;
constexpr int kSpace = 65;
constexpr int kBad = 66;

constexpr std::array<uint8_t, 256> MakeTable() {
  std::array<uint8_t, 256> table{};
  for (auto& entry : table) entry = kBad;
  const char* alphabet = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  for (int i = 0; i < 64; ++i) table[static_cast<unsigned char>(alphabet[i])] = i;
  table['='] = kPad;
  for (char c : {' ', '\t', '\n', '\r', '\f', '\v'}) table[static_cast<unsigned char>(c)] = kSpace;
  return table;
}

constexpr std::array<uint8_t, 256> kTable = MakeTable();

}  // namespace

std::string Base64Encode(absl::string_view bytes) { return absl::Base64Escape(bytes); }

absl::StatusOr<std::string> Base64Decode(absl::string_view text) {
  std::string out;
  out.reserve(text.size() / 4 * 3);
  uint8_t group[4];
  int filled = 0;
  for (size_t i = 0; i < text.size(); ++i) {
    const uint8_t code = kTable[static_cast<unsigned char>(text[i])];
    if (code == kSpace) continue;
    if (code == kBad) {
      return absl::InvalidArgumentError(
          absl::StrCat("invalid base64 character (byte ",
                       static_cast<int>(static_cast<unsigned char>(text[i])), ") at offset ", i));
    }
    group[filled++] = code;
    if (filled < 4) continue;
    filled = 0;
    // Padding may only end a group: "xx==" or "xxx=".
    if (group[0] == kPad || group[1] == kPad || (group[2] == kPad && group[3] != kPad)) {
      return absl::InvalidArgumentError(absl::StrCat("misplaced base64 padding near offset ", i));
    }
    out.push_back(static_cast<char>((group[0] << 2) | (group[1] >> 4)));
    if (group[2] == kPad) continue;
    out.push_back(static_cast<char>(((group[1] & 0x0f) << 4) | (group[2] >> 2)));
    if (group[3] == kPad) continue;
    out.push_back(static_cast<char>(((group[2] & 0x03) << 6) | group[3]));
  }
  if (filled != 0) {
    return absl::InvalidArgumentError(absl::StrCat("base64 text ends in a partial group of ",
                                                   filled,
                                                   " characters "
                                                   "(truncated?)"));
  }
  return out;
}

}  // namespace tetrefine::io
