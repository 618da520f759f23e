#include "client/io/header_lines.h"

namespace tetrefine::io {

bool HeaderLines::Next(absl::string_view& line) {
  if (offset_ >= bytes_.size()) return false;
  const size_t end = bytes_.find('\n', offset_);
  last_unterminated_ = end == absl::string_view::npos;
  const size_t stop = last_unterminated_ ? bytes_.size() : end;
  line = bytes_.substr(offset_, stop - offset_);
  if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
  offset_ = last_unterminated_ ? bytes_.size() : end + 1;
  ++line_number_;
  return true;
}

}  // namespace tetrefine::io
