// Reading VTK XML unstructured grids (.vtu) with pugixml. See vtu_format.h for what is read.
#include <algorithm>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "absl/strings/match.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/strip.h"
#include "client/io/io_error.h"
#include "client/io/label_names.h"
#include "client/io/mesh_frame.h"
#include "client/io/number_text.h"
#include "client/io/vtk_cells.h"
#include "client/io/vtu_data_array.h"
#include "client/io/vtu_format.h"
#include "core/huge_pages.h"
#include "pugixml.hpp"

namespace tetrefine::io {
namespace {

// The XML part of the file, ready for pugixml, and the appended section cut off from it. Raw
// appended data is not XML (any byte may follow the '_'), so the document handed to the parser
// ends with the <AppendedData> start tag, closed by hand; VTK's own reader does the same.
struct SplitFile {
  std::string xml;
  VtuAppended appended;
};

bool IsXmlSpace(char c) { return c == ' ' || c == '\t' || c == '\n' || c == '\r'; }

absl::StatusOr<SplitFile> Split(absl::string_view text, absl::string_view path) {
  SplitFile split;
  const size_t tag = text.find("<AppendedData");
  if (tag == absl::string_view::npos) {
    split.xml.assign(text.data(), text.size());
    return split;
  }
  const size_t gt = text.find('>', tag);
  if (gt == absl::string_view::npos) return FileError(path, "<AppendedData> tag is not closed");
  if (text[gt - 1] == '/') {  // <AppendedData .../>: an empty section
    split.xml = absl::StrCat(text.substr(0, gt + 1), "</VTKFile>");
    return split;
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
  split.appended.present = true;
  split.appended.data = text.substr(underscore + 1);
  split.xml = absl::StrCat(text.substr(0, gt + 1), "</AppendedData></VTKFile>");
  return split;
}

int64_t LineAt(absl::string_view text, ptrdiff_t offset) {
  if (offset < 0) return 0;
  const size_t end = std::min<size_t>(offset, text.size());
  return 1 + std::count(text.begin(), text.begin() + end, '\n');
}

bool AttributeInt(pugi::xml_node node, const char* key, int64_t& out) {
  const pugi::xml_attribute a = node.attribute(key);
  return a && ParseInt64(a.value(), out);
}

int64_t Components(pugi::xml_node node) {
  int64_t n = 1;
  if (node.attribute("NumberOfComponents") && !AttributeInt(node, "NumberOfComponents", n)) {
    return -1;
  }
  return n;
}

// The frame named by a "SPACE" string array in field data (what 3D Slicer writes).
absl::StatusOr<MeshFrame> FieldDataFrame(pugi::xml_node grid, VtuArrayReader& arrays) {
  for (pugi::xml_node array : grid.child("FieldData").children()) {
    if (absl::string_view(array.attribute("Name").value()) != "SPACE") continue;
    absl::StatusOr<std::string> bytes = arrays.StringBytes(array);
    if (!bytes.ok()) return bytes.status();
    const absl::string_view first(bytes->c_str());  // up to the first NUL
    if (absl::StrContains(first, "LPS")) return MeshFrame::kLps;
    if (absl::StrContains(first, "RAS")) return MeshFrame::kRas;
  }
  return MeshFrame::kUntagged;
}

}  // namespace

absl::StatusOr<MeshFile> ParseVtu(absl::string_view text, absl::string_view path) {
  absl::StatusOr<SplitFile> split = Split(text, path);
  if (!split.ok()) return split.status();
  pugi::xml_document doc;
  const pugi::xml_parse_result parsed = doc.load_buffer_inplace(
      split->xml.data(), split->xml.size(), pugi::parse_default, pugi::encoding_utf8);
  if (!parsed) {
    return FileLineError(path, LineAt(text, parsed.offset),
                         absl::StrCat("not well-formed XML: ", parsed.description()));
  }
  // pugixml's offsets point into its own buffer, a copy of the file's first bytes.
  const char* base = split->xml.data();
  const auto line_of = [text, base](pugi::xml_node node) {
    return node.type() == pugi::node_element && node.name()[0] != '\0'
               ? LineAt(text, node.name() - base)
               : int64_t{0};
  };

  const pugi::xml_node root = doc.document_element();
  if (absl::string_view(root.name()) != "VTKFile") {
    return FileError(path, "root element is not <VTKFile>");
  }
  const absl::string_view type = root.attribute("type").value();
  if (type != "UnstructuredGrid") {
    return FileError(
        path, absl::StrCat("VTKFile type \"", type.substr(0, 40), "\" is not UnstructuredGrid"));
  }
  VtuEncoding enc;
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
  if (split->appended.present) {
    const absl::string_view encoding = root.child("AppendedData").attribute("encoding").value();
    if (encoding == "base64") {
      split->appended.base64 = true;
    } else if (encoding != "raw") {
      return FileError(path, absl::StrCat("<AppendedData> encoding \"", encoding.substr(0, 40),
                                          "\" is neither raw nor base64"));
    }
  }

  const pugi::xml_node grid = root.child("UnstructuredGrid");
  if (!grid) return FileError(path, "no <UnstructuredGrid>");
  std::vector<pugi::xml_node> pieces;
  for (pugi::xml_node piece : grid.children("Piece")) pieces.push_back(piece);
  if (pieces.empty()) return FileError(path, "no <Piece>");
  if (pieces.size() > 1) {
    return FileUnsupported(path, absl::StrCat(pieces.size(),
                                              " <Piece>s; merge them into one first (their "
                                              "shared points are duplicated)"));
  }
  const pugi::xml_node piece = pieces[0];
  int64_t v = -1;
  int64_t n = -1;
  if (!AttributeInt(piece, "NumberOfPoints", v) || !AttributeInt(piece, "NumberOfCells", n) ||
      v < 0 || v > int64_t{0xffffffff} || n < 0 || n > (int64_t{1} << 40)) {
    return FileLineError(path, line_of(piece),
                         "Piece needs valid NumberOfPoints and NumberOfCells");
  }

  VtuArrayReader arrays(path, enc, split->appended, line_of);
  MeshFile file;
  absl::StatusOr<MeshFrame> frame = FieldDataFrame(grid, arrays);
  if (!frame.ok()) return frame.status();
  file.frame = *frame;

  const pugi::xml_node points_array = piece.child("Points").child("DataArray");
  if (!points_array) return FileError(path, "no <Points><DataArray>");
  if (Components(points_array) != 3) {
    return FileLineError(path, line_of(points_array), "Points DataArray must have 3 components");
  }
  absl::StatusOr<std::vector<double>> xyz = arrays.Doubles(points_array, 3 * v);
  if (!xyz.ok()) return xyz.status();
  ReserveHuge(file.mesh.points, v);
  file.mesh.points.resize(v);
  for (int64_t i = 0; i < v; ++i) {
    file.mesh.points[i] = {(*xyz)[3 * i], (*xyz)[3 * i + 1], (*xyz)[3 * i + 2]};
  }
  xyz->clear();
  xyz->shrink_to_fit();

  const pugi::xml_node cells = piece.child("Cells");
  if (!cells) return FileError(path, "no <Cells>");
  pugi::xml_node connectivity_array, offsets_array, types_array;
  for (pugi::xml_node child : cells.children("DataArray")) {
    const absl::string_view name = child.attribute("Name").value();
    if (name == "connectivity") connectivity_array = child;
    if (name == "offsets") offsets_array = child;
    if (name == "types") types_array = child;
  }
  if (!connectivity_array || !offsets_array || !types_array) {
    return FileLineError(path, line_of(cells),
                         "Cells needs connectivity, offsets and types arrays");
  }
  VtkCells vtk;
  absl::StatusOr<std::vector<int64_t>> offsets = arrays.Int64s(offsets_array, n);
  if (!offsets.ok()) return offsets.status();
  absl::StatusOr<std::vector<int64_t>> types = arrays.Int64s(types_array, n);
  if (!types.ok()) return types.status();
  // XML offsets are cell ends; VtkCells wants a leading 0.
  const int64_t connectivity_size = n == 0 ? 0 : offsets->back();
  if (connectivity_size < 0 || connectivity_size > (int64_t{1} << 44)) {
    return FileLineError(path, line_of(offsets_array), "last cell offset is out of range");
  }
  absl::StatusOr<std::vector<int64_t>> connectivity =
      arrays.Int64s(connectivity_array, connectivity_size);
  if (!connectivity.ok()) return connectivity.status();
  vtk.offsets.reserve(n + 1);
  vtk.offsets.push_back(0);
  vtk.offsets.insert(vtk.offsets.end(), offsets->begin(), offsets->end());
  vtk.types = *std::move(types);
  vtk.connectivity = *std::move(connectivity);

  VtkCellData cell_data;
  for (pugi::xml_node child : piece.child("CellData").children("DataArray")) {
    const std::string name = child.attribute("Name").value();
    if (Components(child) != 1) {
      file.dropped_arrays.push_back(DroppedArray(false, name));
      continue;
    }
    if (name == "iteration" || name == "quality") {
      absl::StatusOr<std::vector<double>> values = arrays.Doubles(child, n);
      if (!values.ok()) return values.status();
      (name == "iteration" ? cell_data.iteration : cell_data.quality) = *std::move(values);
      continue;
    }
    const int rank = LabelNameRank(name);
    if (rank < 0 || (cell_data.label_rank >= 0 && rank >= cell_data.label_rank)) {
      file.dropped_arrays.push_back(DroppedArray(false, name));
      continue;
    }
    absl::StatusOr<std::vector<int64_t>> labels = arrays.Int64s(child, n);
    if (!labels.ok()) return labels.status();
    // A label array the file prefers (LabelNameRank) replaces one read before.
    if (cell_data.label_rank >= 0) {
      file.dropped_arrays.push_back(DroppedArray(false, cell_data.label_name));
    }
    cell_data.label = *std::move(labels);
    cell_data.label_name = name;
    cell_data.label_rank = rank;
  }
  for (pugi::xml_node child : piece.child("PointData").children("DataArray")) {
    if (absl::string_view(child.attribute("Name").value()) != "value" || Components(child) != 1) {
      file.dropped_arrays.push_back(DroppedArray(true, child.attribute("Name").value()));
      continue;
    }
    absl::StatusOr<std::vector<double>> values = arrays.Doubles(child, v);
    if (!values.ok()) return values.status();
    file.mesh.values = *std::move(values);
  }
  if (absl::Status s = CellsToTets(vtk, cell_data, v, path, file); !s.ok()) return s;
  FrameToRas(file);
  if (absl::Status s = ValidateMeshFile(file, path); !s.ok()) return s;
  return file;
}

}  // namespace tetrefine::io
