#include "client/io/text_scanner.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "absl/strings/match.h"
#include "absl/strings/str_cat.h"
#include "client/io/io_error.h"
#include "client/io/number_text.h"

namespace tetrefine::io {
namespace {

bool IsSpace(char c) {
  return c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\f' || c == '\v';
}

}  // namespace

std::string QuoteToken(absl::string_view token) {
  std::string out = "\"";
  for (char c : token.substr(0, 40)) out.push_back(c >= 32 && c < 127 ? c : '?');
  if (token.size() > 40) out += "...";
  out += "\"";
  return out;
}

void TextScanner::SkipSpace() {
  while (pos_ < text_.size()) {
    const char c = text_[pos_];
    if (c == '\n') {
      ++line_;
      ++pos_;
    } else if (IsSpace(c)) {
      ++pos_;
    } else if (comment_ != '\0' && c == comment_) {
      while (pos_ < text_.size() && text_[pos_] != '\n') ++pos_;
    } else {
      break;
    }
  }
}

bool TextScanner::AtEnd() {
  SkipSpace();
  return pos_ >= text_.size();
}

absl::StatusOr<absl::string_view> TextScanner::Token(absl::string_view what) {
  SkipSpace();
  if (pos_ >= text_.size()) {
    return Error(absl::StrCat("unexpected end of file (truncated?), expected ", what));
  }
  const size_t start = pos_;
  while (pos_ < text_.size() && !IsSpace(text_[pos_]) &&
         !(comment_ != '\0' && text_[pos_] == comment_)) {
    ++pos_;
  }
  return text_.substr(start, pos_ - start);
}

absl::StatusOr<double> TextScanner::Double(absl::string_view what) {
  absl::StatusOr<absl::string_view> token = Token(what);
  if (!token.ok()) return token.status();
  double value;
  if (!ParseDouble(*token, value)) {
    return Error(absl::StrCat("expected ", what, " (a number), got ", QuoteToken(*token)));
  }
  return value;
}

absl::StatusOr<double> TextScanner::FiniteDouble(absl::string_view what) {
  absl::StatusOr<double> value = Double(what);
  if (value.ok() && !std::isfinite(*value)) {
    return Error(absl::StrCat(what, " is not finite (", *value, ")"));
  }
  return value;
}

absl::StatusOr<int64_t> TextScanner::Int(absl::string_view what) {
  absl::StatusOr<absl::string_view> token = Token(what);
  if (!token.ok()) return token.status();
  int64_t value;
  if (!ParseInt64(*token, value)) {
    return Error(absl::StrCat("expected ", what, " (an integer), got ", QuoteToken(*token)));
  }
  return value;
}

absl::StatusOr<int64_t> TextScanner::IntIn(absl::string_view what, int64_t lo, int64_t hi) {
  absl::StatusOr<int64_t> value = Int(what);
  if (value.ok() && (*value < lo || *value > hi)) {
    return Error(absl::StrCat(what, " = ", *value, " is out of range [", lo, ", ", hi, "]"));
  }
  return value;
}

bool TextScanner::ConsumeIf(absl::string_view word) {
  SkipSpace();
  const size_t saved_pos = pos_;
  const int64_t saved_line = line_;
  absl::StatusOr<absl::string_view> token = Token(word);
  if (token.ok() && absl::EqualsIgnoreCase(*token, word)) return true;
  pos_ = saved_pos;
  line_ = saved_line;
  return false;
}

absl::string_view TextScanner::RestOfLine() {
  size_t end = pos_;
  while (end < text_.size() && text_[end] != '\n') ++end;
  absl::string_view rest = text_.substr(pos_, end - pos_);
  if (!rest.empty() && rest.back() == '\r') rest.remove_suffix(1);
  pos_ = end;
  if (pos_ < text_.size()) {
    ++pos_;
    ++line_;
  }
  return rest;
}

absl::string_view TextScanner::PeekRestOfLine() const {
  size_t end = pos_;
  while (end < text_.size() && text_[end] != '\n' && (comment_ == '\0' || text_[end] != comment_)) {
    ++end;
  }
  absl::string_view rest = text_.substr(pos_, end - pos_);
  if (!rest.empty() && rest.back() == '\r') rest.remove_suffix(1);
  return rest;
}

absl::StatusOr<absl::string_view> TextScanner::Bytes(size_t n, absl::string_view what) {
  if (n > remaining()) {
    return Error(
        absl::StrCat("truncated: ", what, " needs ", n, " bytes, only ", remaining(), " remain"));
  }
  const absl::string_view out = text_.substr(pos_, n);
  line_ += std::count(out.begin(), out.end(), '\n');
  pos_ += n;
  return out;
}

absl::Status TextScanner::CheckCount(int64_t count, int64_t min_bytes, absl::string_view what) {
  // No whitespace skipping here: in binary files the next bytes are data, not separators.
  if (count < 0) return Error(absl::StrCat("negative count of ", what, ": ", count));
  const int64_t left = static_cast<int64_t>(remaining());
  if (count > 0 && count > left / min_bytes) {
    return Error(absl::StrCat("declares ", count, " ", what, " but only ", left,
                              " bytes remain (truncated or corrupt count)"));
  }
  return absl::OkStatus();
}

absl::Status TextScanner::Error(absl::string_view problem) const {
  return FileLineError(path_, line_, problem);
}

absl::Status TextScanner::ErrorAt(int64_t line, absl::string_view problem) const {
  return FileLineError(path_, line, problem);
}

}  // namespace tetrefine::io
