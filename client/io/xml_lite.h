#pragma once

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "absl/status/statusor.h"
#include "absl/strings/string_view.h"

namespace tetrefine::io {

// An element of a small XML document: enough for VTK XML files, which use elements, attributes
// and character data only. Character data is a view into the parsed text, which must outlive
// the tree.
struct XmlElement {
  std::string name;
  std::vector<std::pair<std::string, std::string>> attributes;  // entity references decoded
  std::vector<XmlElement> children;
  absl::string_view text;  // character data of a leaf element, raw (no entity decoding)
  int64_t line = 0;        // 1-based line of the start tag

  // The attribute's value, or nullptr.
  const std::string* Attribute(absl::string_view key) const;
  // The first child named `child_name`, or nullptr.
  const XmlElement* Child(absl::string_view child_name) const;
};

// Parses a document into its root element. Skips the XML declaration, comments, processing
// instructions and DOCTYPE; rejects CDATA sections and unbalanced or truncated markup. Nesting is
// limited (depth 64) so hostile input cannot overflow the stack. Errors are "<path>:<line>: ...".
absl::StatusOr<XmlElement> ParseXml(absl::string_view text, absl::string_view path);

}  // namespace tetrefine::io
