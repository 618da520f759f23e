#pragma once

#include <cstdint>

#include "absl/strings/string_view.h"

namespace tetrefine::io {

// Walks the text header of a NRRD or MetaImage file line by line, keeping the byte offset where
// the binary payload starts (right after the line terminator of the last line consumed).
class HeaderLines {
 public:
  explicit HeaderLines(absl::string_view bytes) : bytes_(bytes) {}

  // Next line without its terminator ("\n" or "\r\n"); false at end of input.
  bool Next(absl::string_view& line);

  // Byte offset just past the last line returned.
  size_t offset() const { return offset_; }
  // 1-based number of the last line returned.
  int64_t line_number() const { return line_number_; }
  // True when the last line returned ended at end of input without a terminator.
  bool last_unterminated() const { return last_unterminated_; }

 private:
  absl::string_view bytes_;
  size_t offset_ = 0;
  int64_t line_number_ = 0;
  bool last_unterminated_ = false;
};

}  // namespace tetrefine::io
