#pragma once

#include <cstdint>
#include <string>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "absl/strings/string_view.h"

namespace tetrefine::io {

// `token` quoted for a message: at most 40 characters, bytes outside printable ASCII as '?', so
// binary garbage cannot flood or corrupt an error line.
std::string QuoteToken(absl::string_view token);

// Splits an ASCII mesh file into whitespace-separated tokens, tracking line numbers so every
// error can say "<path>:<line>: <problem>".
class TextScanner {
 public:
  // `comment` (if not '\0') starts a comment running to the end of its line.
  TextScanner(absl::string_view text, absl::string_view path, char comment = '\0')
      : text_(text), path_(path), comment_(comment) {}

  // True when only whitespace (and comments) remain.
  bool AtEnd();
  // True when nothing at all remains (AtEnd skips blank lines; this does not).
  bool AtEndOfInput() const { return pos_ >= text_.size(); }

  // The next token; an "unexpected end of file" error naming `what` when there is none.
  absl::StatusOr<absl::string_view> Token(absl::string_view what);
  // The next token as a number; errors name `what` and quote the bad token.
  absl::StatusOr<double> Double(absl::string_view what);
  absl::StatusOr<double> FiniteDouble(absl::string_view what);
  absl::StatusOr<int64_t> Int(absl::string_view what);
  // An integer in [lo, hi].
  absl::StatusOr<int64_t> IntIn(absl::string_view what, int64_t lo, int64_t hi);

  // Consumes the next token if it equals `word` (ASCII case-insensitive); false otherwise.
  bool ConsumeIf(absl::string_view word);

  // The rest of the current line (after the last token), without the terminator, and moves to
  // the next line. Used for free-text lines such as titles.
  absl::string_view RestOfLine();
  // The same without moving, and without a comment that ends the line: what follows the last
  // token on its line (a reader's check that a line holds as many numbers as it should).
  absl::string_view PeekRestOfLine() const;

  // The next `n` raw bytes, from the current position (no whitespace skipped): the binary block
  // that follows a header line in binary legacy VTK and Gmsh files. Line numbers keep counting
  // the newline bytes inside, so later errors still give the line an editor shows.
  absl::StatusOr<absl::string_view> Bytes(size_t n, absl::string_view what);

  // Fails unless at least `count` entries of at least `min_bytes` each can still follow. Called
  // before reserving memory for a declared count, so a corrupt count cannot allocate more than
  // the file could describe.
  absl::Status CheckCount(int64_t count, int64_t min_bytes, absl::string_view what);

  // "<path>:<line>: <problem>" at the current line.
  absl::Status Error(absl::string_view problem) const;
  // The same at `line` (one a RestOfLine has already passed).
  absl::Status ErrorAt(int64_t line, absl::string_view problem) const;

  int64_t line() const { return line_; }
  size_t remaining() const { return text_.size() - pos_; }

 private:
  void SkipSpace();

  absl::string_view text_;
  absl::string_view path_;
  char comment_;
  size_t pos_ = 0;
  int64_t line_ = 1;
};

}  // namespace tetrefine::io
