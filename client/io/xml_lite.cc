#include "client/io/xml_lite.h"

#include <algorithm>

#include "absl/strings/match.h"
#include "absl/strings/str_cat.h"
#include "client/io/io_error.h"

namespace tetrefine::io {
namespace {

constexpr int kMaxDepth = 64;

bool IsNameChar(char c) {
  return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_' ||
         c == '-' || c == '.' || c == ':';
}

bool IsSpace(char c) { return c == ' ' || c == '\t' || c == '\n' || c == '\r'; }

class Parser {
 public:
  Parser(absl::string_view text, absl::string_view path) : text_(text), path_(path) {}

  absl::StatusOr<XmlElement> Document() {
    if (absl::Status s = SkipMisc(); !s.ok()) return s;
    if (pos_ >= text_.size()) return Error("no root element (empty or not XML)");
    XmlElement root;
    if (absl::Status s = Element(root, 0); !s.ok()) return s;
    if (absl::Status s = SkipMisc(); !s.ok()) return s;
    if (pos_ < text_.size()) return Error("content after the root element");
    return root;
  }

 private:
  absl::Status Error(absl::string_view problem) {
    return FileLineError(path_, LineAt(pos_), problem);
  }

  int64_t LineAt(size_t pos) {
    pos = std::min(pos, text_.size());
    if (pos < line_pos_) {
      line_pos_ = 0;
      line_ = 1;
    }
    line_ += std::count(text_.begin() + line_pos_, text_.begin() + pos, '\n');
    line_pos_ = pos;
    return line_;
  }

  void SkipSpace() {
    while (pos_ < text_.size() && IsSpace(text_[pos_])) ++pos_;
  }

  // Skips whitespace, comments, processing instructions and DOCTYPE before/after the root.
  absl::Status SkipMisc() {
    while (true) {
      SkipSpace();
      if (absl::StartsWith(text_.substr(pos_), "<?")) {
        if (absl::Status s = SkipPast("?>"); !s.ok()) return s;
      } else if (absl::StartsWith(text_.substr(pos_), "<!--")) {
        if (absl::Status s = SkipPast("-->"); !s.ok()) return s;
      } else if (absl::StartsWith(text_.substr(pos_), "<!DOCTYPE")) {
        if (absl::Status s = SkipPast(">"); !s.ok()) return s;
      } else {
        return absl::OkStatus();
      }
    }
  }

  absl::Status SkipPast(absl::string_view terminator) {
    const size_t end = text_.find(terminator, pos_);
    if (end == absl::string_view::npos) {
      return Error(absl::StrCat("truncated: no closing \"", terminator, "\""));
    }
    pos_ = end + terminator.size();
    return absl::OkStatus();
  }

  absl::StatusOr<std::string> Name() {
    const size_t start = pos_;
    while (pos_ < text_.size() && IsNameChar(text_[pos_])) ++pos_;
    if (pos_ == start) {
      if (pos_ >= text_.size()) return Error("truncated inside a tag");
      return Error(absl::StrCat("expected a name in a tag, got '", text_.substr(pos_, 1), "'"));
    }
    return std::string(text_.substr(start, pos_ - start));
  }

  absl::StatusOr<std::string> Unescape(absl::string_view raw) {
    std::string out;
    for (size_t i = 0; i < raw.size(); ++i) {
      if (raw[i] != '&') {
        out.push_back(raw[i]);
        continue;
      }
      const size_t semi = raw.find(';', i);
      if (semi == absl::string_view::npos) return Error("unterminated entity reference");
      const absl::string_view entity = raw.substr(i + 1, semi - i - 1);
      if (entity == "lt") {
        out.push_back('<');
      } else if (entity == "gt") {
        out.push_back('>');
      } else if (entity == "amp") {
        out.push_back('&');
      } else if (entity == "quot") {
        out.push_back('"');
      } else if (entity == "apos") {
        out.push_back('\'');
      } else {
        return Error(absl::StrCat("unsupported entity &", entity.substr(0, 20), ";"));
      }
      i = semi;
    }
    return out;
  }

  // Parses the element starting at pos_ ('<') into `element`.
  absl::Status Element(XmlElement& element, int depth) {
    if (depth > kMaxDepth) return Error("elements nested too deeply");
    element.line = LineAt(pos_);
    ++pos_;  // '<'
    absl::StatusOr<std::string> name = Name();
    if (!name.ok()) return name.status();
    element.name = *std::move(name);
    // Attributes, then '>' or '/>'.
    while (true) {
      SkipSpace();
      if (pos_ >= text_.size()) return Error(absl::StrCat("truncated in <", element.name, ">"));
      if (text_[pos_] == '>') {
        ++pos_;
        break;
      }
      if (absl::StartsWith(text_.substr(pos_), "/>")) {
        pos_ += 2;
        return absl::OkStatus();
      }
      absl::StatusOr<std::string> key = Name();
      if (!key.ok()) return key.status();
      SkipSpace();
      if (pos_ >= text_.size() || text_[pos_] != '=') {
        return Error(absl::StrCat("attribute ", *key, " has no '='"));
      }
      ++pos_;
      SkipSpace();
      if (pos_ >= text_.size() || (text_[pos_] != '"' && text_[pos_] != '\'')) {
        return Error(absl::StrCat("attribute ", *key, " value is not quoted"));
      }
      const char quote = text_[pos_++];
      const size_t end = text_.find(quote, pos_);
      if (end == absl::string_view::npos) return Error("truncated attribute value");
      absl::StatusOr<std::string> value = Unescape(text_.substr(pos_, end - pos_));
      if (!value.ok()) return value.status();
      element.attributes.emplace_back(*std::move(key), *std::move(value));
      pos_ = end + 1;
    }
    // Content up to the matching end tag.
    const size_t content_start = pos_;
    while (true) {
      const size_t open = text_.find('<', pos_);
      if (open == absl::string_view::npos) {
        pos_ = text_.size();
        return Error(absl::StrCat("truncated: <", element.name, "> (line ", element.line,
                                  ") is never closed"));
      }
      pos_ = open;
      const absl::string_view rest = text_.substr(pos_);
      if (absl::StartsWith(rest, "</")) {
        if (element.children.empty()) {
          element.text = text_.substr(content_start, open - content_start);
        }
        pos_ += 2;
        absl::StatusOr<std::string> end_name = Name();
        if (!end_name.ok()) return end_name.status();
        if (*end_name != element.name) {
          return Error(absl::StrCat("</", *end_name, "> closes <", element.name, "> (line ",
                                    element.line, ")"));
        }
        SkipSpace();
        if (pos_ >= text_.size() || text_[pos_] != '>') return Error("truncated end tag");
        ++pos_;
        return absl::OkStatus();
      }
      if (absl::StartsWith(rest, "<!--")) {
        if (absl::Status s = SkipPast("-->"); !s.ok()) return s;
      } else if (absl::StartsWith(rest, "<?")) {
        if (absl::Status s = SkipPast("?>"); !s.ok()) return s;
      } else if (absl::StartsWith(rest, "<!")) {
        return Error("CDATA sections and declarations inside elements are not supported");
      } else {
        element.children.emplace_back();
        if (absl::Status s = Element(element.children.back(), depth + 1); !s.ok()) return s;
      }
    }
  }

  absl::string_view text_;
  absl::string_view path_;
  size_t pos_ = 0;
  size_t line_pos_ = 0;
  int64_t line_ = 1;
};

}  // namespace

const std::string* XmlElement::Attribute(absl::string_view key) const {
  for (const auto& [k, v] : attributes) {
    if (k == key) return &v;
  }
  return nullptr;
}

const XmlElement* XmlElement::Child(absl::string_view child_name) const {
  for (const XmlElement& child : children) {
    if (child.name == child_name) return &child;
  }
  return nullptr;
}

absl::StatusOr<XmlElement> ParseXml(absl::string_view text, absl::string_view path) {
  return Parser(text, path).Document();
}

}  // namespace tetrefine::io
