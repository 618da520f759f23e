#pragma once

// Shared by the fuzz targets: a failure that libFuzzer (or the corpus replay) reports as a crash,
// a reader of fuzz bytes that never runs out, and a private directory for readers that take paths.

#include <cstddef>
#include <cstdint>
#include <initializer_list>
#include <string>
#include <string_view>
#include <vector>

#include "absl/status/statusor.h"

namespace tetrefine::fuzz {

// Prints `what` and aborts: an invariant the target asserts does not hold.
[[noreturn]] void Fail(const char* file, int line, const std::string& what);

#define TETREFINE_FUZZ_CHECK(condition, what)                                               \
  do {                                                                                      \
    if (!(condition))                                                                       \
      ::tetrefine::fuzz::Fail(__FILE__, __LINE__, std::string(#condition) + ": " + (what)); \
  } while (false)

// Reads the fuzz input front to back; past the end every read gives zeros, so any input decodes.
class ByteSource {
 public:
  ByteSource(const uint8_t* data, size_t size) : data_(data), size_(size) {}

  uint8_t Byte() { return offset_ < size_ ? data_[offset_++] : 0; }
  uint16_t U16() { return static_cast<uint16_t>(Byte() | (Byte() << 8)); }
  // An integer in [lo, hi].
  int Int(int lo, int hi) {
    return lo + static_cast<int>(U16() % static_cast<unsigned>(hi - lo + 1));
  }
  // `n` raw bytes (fewer when the input runs out).
  std::string_view Bytes(size_t n);
  std::string_view Rest() { return Bytes(size_ - offset_); }
  size_t remaining() const { return size_ - offset_; }

 private:
  const uint8_t* data_;
  size_t size_;
  size_t offset_ = 0;
};

// True when a line of `text` containing one of `keys` (compared case-insensitively; give them in
// lower case) also contains `c`.
bool AnyKeyLineContains(std::string_view text, std::initializer_list<std::string_view> keys,
                        char c);

// `name` inside a directory private to this process (created on first use, under $TMPDIR or
// /tmp), with `bytes` written to it. Readers that only take paths read it from there.
std::string WritePrivateFile(std::string_view name, std::string_view bytes);

// What a parallel index parser (.pvtu, .pvti) promises for any input: an error with a message,
// or at least one piece, each a non-empty path.
void CheckPieceSources(const absl::StatusOr<std::vector<std::string>>& sources);

}  // namespace tetrefine::fuzz
