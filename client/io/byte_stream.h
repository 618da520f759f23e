#pragma once

#include <cstddef>
#include <string>

#include "absl/status/statusor.h"
#include "absl/strings/string_view.h"

namespace tetrefine::io {

// Reads bytes in sequence from raw storage or from base64 text (VTK XML inline "binary" arrays
// and base64-encoded appended data). Base64 groups are decoded one by one, so blocks that were
// encoded and padded separately (VTK encodes a compressed array's header apart from its data)
// read as their concatenation. Errors carry no path; callers add it.
class ByteStream {
 public:
  static ByteStream Raw(absl::string_view bytes) { return ByteStream(bytes, false); }
  static ByteStream Base64(absl::string_view text) { return ByteStream(text, true); }

  // The next `n` bytes, valid until the next call; an error when fewer remain. The check comes
  // before any allocation, so a corrupt count cannot allocate more than the input could hold.
  absl::StatusOr<absl::string_view> Read(size_t n);

  // At most how many bytes are left (exact for raw storage).
  size_t MaxRemaining() const;

 private:
  ByteStream(absl::string_view source, bool base64) : source_(source), base64_(base64) {}

  absl::string_view source_;
  bool base64_;
  size_t pos_ = 0;
  std::string decoded_;   // base64: the bytes handed out by the last Read, then leftovers
  std::string leftover_;  // base64: decoded bytes of a group not yet handed out
};

}  // namespace tetrefine::io
