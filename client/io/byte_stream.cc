#include "client/io/byte_stream.h"

#include <array>
#include <cstdint>

#include "absl/status/status.h"
#include "absl/strings/str_cat.h"

namespace tetrefine::io {
namespace {

constexpr uint8_t kPad = 64;
constexpr uint8_t kSpace = 65;
constexpr uint8_t kBad = 66;

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

size_t ByteStream::MaxRemaining() const {
  const size_t left = source_.size() - pos_;
  return base64_ ? leftover_.size() + left / 4 * 3 + 3 : left;
}

absl::StatusOr<absl::string_view> ByteStream::Read(size_t n) {
  if (n > MaxRemaining()) {
    return absl::InvalidArgumentError(
        absl::StrCat("needs ", n, " more bytes, only ", MaxRemaining(), " remain (truncated?)"));
  }
  if (!base64_) {
    const absl::string_view out = source_.substr(pos_, n);
    pos_ += n;
    return out;
  }
  decoded_.clear();
  decoded_.reserve(n);
  const size_t from_leftover = std::min(n, leftover_.size());
  decoded_.append(leftover_, 0, from_leftover);
  leftover_.erase(0, from_leftover);
  uint8_t group[4];
  int filled = 0;
  while (decoded_.size() < n) {
    if (pos_ >= source_.size()) {
      return absl::InvalidArgumentError(absl::StrCat("base64 data ends after ", decoded_.size(),
                                                     " of ", n, " bytes (truncated?)"));
    }
    const uint8_t code = kTable[static_cast<unsigned char>(source_[pos_])];
    ++pos_;
    if (code == kSpace) continue;
    if (code == kBad) {
      return absl::InvalidArgumentError(
          absl::StrCat("invalid base64 character (byte ",
                       static_cast<int>(static_cast<unsigned char>(source_[pos_ - 1])), ")"));
    }
    group[filled++] = code;
    if (filled < 4) continue;
    filled = 0;
    // Padding may only end a group: "xx==" or "xxx=".
    if (group[0] == kPad || group[1] == kPad || (group[2] == kPad && group[3] != kPad)) {
      return absl::InvalidArgumentError("misplaced base64 padding");
    }
    char bytes[3];
    int count = 1;
    bytes[0] = static_cast<char>((group[0] << 2) | (group[1] >> 4));
    if (group[2] != kPad) {
      bytes[count++] = static_cast<char>(((group[1] & 0x0f) << 4) | (group[2] >> 2));
      if (group[3] != kPad) bytes[count++] = static_cast<char>(((group[2] & 0x03) << 6) | group[3]);
    }
    const size_t take = std::min<size_t>(count, n - decoded_.size());
    decoded_.append(bytes, take);
    leftover_.append(bytes + take, count - take);
  }
  return absl::string_view(decoded_);
}

}  // namespace tetrefine::io
