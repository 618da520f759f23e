#include "client/io/vtk_xml_file.h"

#include <algorithm>
#include <filesystem>
#include <optional>

#include "absl/strings/match.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/strip.h"
#include "client/io/io_error.h"

namespace tetrefine::io {
namespace {

bool IsXmlSpace(char c) { return c == ' ' || c == '\t' || c == '\n' || c == '\r'; }

// Cuts the appended section off `text`: out.xml gets the XML part, closed by hand after the
// <AppendedData> start tag, and out.appended the bytes after the '_' marker.
absl::Status Split(absl::string_view text, absl::string_view path, VtkXmlFile& out) {
  const size_t tag = text.find("<AppendedData");
  if (tag == absl::string_view::npos) {
    out.xml.assign(text.data(), text.size());
    return absl::OkStatus();
  }
  const size_t gt = text.find('>', tag);
  if (gt == absl::string_view::npos) return FileError(path, "<AppendedData> tag is not closed");
  if (text[gt - 1] == '/') {  // <AppendedData .../>: an empty section
    out.xml = absl::StrCat(text.substr(0, gt + 1), "</VTKFile>");
    return absl::OkStatus();
  }
  size_t underscore = gt + 1;
  while (underscore < text.size() && IsXmlSpace(text[underscore])) {
    ++underscore;
  }
  if (underscore >= text.size() || text[underscore] != '_') {
    return FileError(path, "<AppendedData> does not start with the '_' marker");
  }
  // Appended data is read by offsets, so a file cut short after its last array would still
  // read; the closing tags VTK writes after the data tell a complete file from a truncated one.
  absl::string_view tail = text.substr(underscore + 1);
  while (!tail.empty() && IsXmlSpace(tail.back())) tail.remove_suffix(1);
  if (!absl::ConsumeSuffix(&tail, "</VTKFile>")) {
    return FileError(path, "truncated: the file does not end with </VTKFile>");
  }
  while (!tail.empty() && IsXmlSpace(tail.back())) tail.remove_suffix(1);
  if (!absl::EndsWith(tail, "</AppendedData>")) {
    return FileError(path, "truncated: </AppendedData> does not end the file");
  }
  out.appended.present = true;
  out.appended.data = text.substr(underscore + 1);
  out.xml = absl::StrCat(text.substr(0, gt + 1), "</AppendedData></VTKFile>");
  return absl::OkStatus();
}

int64_t LineAt(absl::string_view text, ptrdiff_t offset) {
  if (offset < 0) return 0;
  const size_t end = std::min<size_t>(offset, text.size());
  return 1 + std::count(text.begin(), text.begin() + end, '\n');
}

}  // namespace

int64_t VtkXmlFile::LineOf(pugi::xml_node node) const {
  // pugixml's names point into its own buffer, a copy of the file's first bytes.
  return node.type() == pugi::node_element && node.name()[0] != '\0'
             ? LineAt(text, node.name() - xml.data())
             : int64_t{0};
}

absl::Status OpenVtkXml(absl::string_view text, absl::string_view path, absl::string_view type,
                        VtkXmlFile& out) {
  out.text = text;
  if (absl::Status s = Split(text, path, out); !s.ok()) return s;
  const pugi::xml_parse_result parsed = out.doc.load_buffer_inplace(
      out.xml.data(), out.xml.size(), pugi::parse_default, pugi::encoding_utf8);
  if (!parsed) {
    return FileLineError(path, LineAt(text, parsed.offset),
                         absl::StrCat("not well-formed XML: ", parsed.description()));
  }
  const pugi::xml_node root = out.doc.document_element();
  if (absl::string_view(root.name()) != "VTKFile") {
    return FileError(path, "root element is not <VTKFile>");
  }
  const absl::string_view file_type = root.attribute("type").value();
  if (file_type != type) {
    return FileError(path,
                     absl::StrCat("VTKFile type \"", file_type.substr(0, 40), "\" is not ", type));
  }
  VtuEncoding& enc = out.encoding;
  const absl::string_view order = root.attribute("byte_order").value();
  if (order == "BigEndian") {
    enc.order = ByteOrder::kBig;
  } else if (!order.empty() && order != "LittleEndian") {
    return FileError(path, absl::StrCat("unknown byte_order \"", order.substr(0, 40), "\""));
  }
  const absl::string_view header_type = root.attribute("header_type").value();
  if (header_type == "UInt64") {
    enc.header_bytes = 8;
  } else if (!header_type.empty() && header_type != "UInt32") {
    return FileError(path, absl::StrCat("unknown header_type \"", header_type.substr(0, 40), "\""));
  }
  if (const pugi::xml_attribute compressor = root.attribute("compressor")) {
    const std::optional<VtkCompressor> c = VtkCompressorFromName(compressor.value());
    if (!c) {
      return FileUnsupported(
          path, absl::StrCat("compressor \"", absl::string_view(compressor.value()).substr(0, 40),
                             "\" is not supported (zlib, lzma and lz4 are)"));
    }
    enc.compressor = *c;
  }
  if (out.appended.present) {
    const absl::string_view encoding = root.child("AppendedData").attribute("encoding").value();
    if (encoding == "base64") {
      out.appended.base64 = true;
    } else if (encoding != "raw") {
      return FileError(path, absl::StrCat("<AppendedData> encoding \"", encoding.substr(0, 40),
                                          "\" is neither raw nor base64"));
    }
  }
  const std::string element(type);
  out.dataset = root.child(element.c_str());
  if (!out.dataset) return FileError(path, absl::StrCat("no <", type, ">"));
  return absl::OkStatus();
}

absl::StatusOr<std::vector<std::string>> PieceSources(const VtkXmlFile& xml,
                                                      absl::string_view path) {
  const std::filesystem::path directory = std::filesystem::path(std::string(path)).parent_path();
  std::vector<std::string> sources;
  for (pugi::xml_node piece : xml.dataset.children("Piece")) {
    const absl::string_view source = piece.attribute("Source").value();
    if (source.empty()) return FileLineError(path, xml.LineOf(piece), "Piece has no Source file");
    const std::filesystem::path p{std::string(source)};
    sources.push_back(p.is_absolute() ? p.string() : (directory / p).string());
  }
  if (sources.empty()) return FileError(path, "no <Piece Source=...>: the index names no pieces");
  return sources;
}

}  // namespace tetrefine::io
