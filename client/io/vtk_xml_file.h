#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "absl/strings/string_view.h"
#include "client/io/vtu_data_array.h"
#include "pugixml.hpp"

namespace tetrefine::io {

// A VTK XML file (.vtu, .vti) as its readers need it: the XML parsed by pugixml, the encoding
// attributes of <VTKFile> (byte order, header type, compressor) and the appended section.
// Raw appended data is not XML (any byte may follow the '_'), so the document handed to the
// parser ends with the <AppendedData> start tag, closed by hand, as VTK's own reader does.
// Not copyable: `doc` points into `xml`.
struct VtkXmlFile {
  VtkXmlFile() = default;
  VtkXmlFile(const VtkXmlFile&) = delete;
  VtkXmlFile& operator=(const VtkXmlFile&) = delete;

  // The root <VTKFile> element's child named after the file's type (<UnstructuredGrid>, ...).
  pugi::xml_node dataset;
  VtuEncoding encoding;
  VtuAppended appended;  // a view into the caller's `text`

  // The 1-based line of `node` in the file (0 for nodes that are not elements), for messages.
  int64_t LineOf(pugi::xml_node node) const;

  std::string xml;  // the buffer pugixml parsed in place
  pugi::xml_document doc;
  absl::string_view text;  // the whole file, the caller's
};

// Parses `text` (the whole file, which must outlive `out`) as a VTK XML file whose
// <VTKFile type="..."> is `type` ("UnstructuredGrid", "ImageData"). Errors name `path` (and the
// line where XML is not well-formed): not XML, another root or type, an unknown byte order,
// header type or appended encoding, a compressor other than zlib, lzma and lz4 (UNIMPLEMENTED),
// an appended section without its '_' marker or cut short before </VTKFile>, no <type> element.
absl::Status OpenVtkXml(absl::string_view text, absl::string_view path, absl::string_view type,
                        VtkXmlFile& out);

// The files a parallel index (.pvtu, .pvti) names in its <Piece Source="..."/> elements, in
// order, each resolved against the directory of `path` unless absolute. Errors name `path` (and
// the line): a piece without a Source, no pieces at all.
absl::StatusOr<std::vector<std::string>> PieceSources(const VtkXmlFile& xml,
                                                      absl::string_view path);

}  // namespace tetrefine::io
