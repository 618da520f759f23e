#include "client/io/vtu_format.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <utility>
#include <vector>

#include "absl/strings/ascii.h"
#include "absl/strings/match.h"
#include "absl/strings/str_cat.h"
#include "client/io/base64.h"
#include "client/io/byte_order.h"
#include "client/io/io_error.h"
#include "client/io/number_text.h"
#include "client/io/vtk_cells.h"
#include "client/io/xml_lite.h"
#include "client/io/zlib_codec.h"

namespace tetrefine::io {
namespace {

// zlib cannot expand data by more than about 1032:1; a header claiming more is corrupt.
constexpr uint64_t kMaxInflateRatio = 1100;

struct Encoding {
  ByteOrder order = ByteOrder::kLittle;
  size_t header_bytes = 4;  // UInt32 or UInt64 block headers
  bool zlib = false;
};

// Size in bytes of a VTK scalar type name; 0 when unknown.
size_t TypeSize(absl::string_view type) {
  if (type == "Int8" || type == "UInt8") return 1;
  if (type == "Int16" || type == "UInt16") return 2;
  if (type == "Int32" || type == "UInt32" || type == "Float32") return 4;
  if (type == "Int64" || type == "UInt64" || type == "Float64") return 8;
  return 0;
}

double LoadValue(absl::string_view bytes, size_t offset, absl::string_view type, ByteOrder order) {
  if (type == "Int8") return LoadAs<int8_t>(bytes, offset, order);
  if (type == "UInt8") return LoadAs<uint8_t>(bytes, offset, order);
  if (type == "Int16") return LoadAs<int16_t>(bytes, offset, order);
  if (type == "UInt16") return LoadAs<uint16_t>(bytes, offset, order);
  if (type == "Int32") return LoadAs<int32_t>(bytes, offset, order);
  if (type == "UInt32") return LoadAs<uint32_t>(bytes, offset, order);
  if (type == "Int64") return static_cast<double>(LoadAs<int64_t>(bytes, offset, order));
  if (type == "UInt64") return static_cast<double>(LoadAs<uint64_t>(bytes, offset, order));
  if (type == "Float32") return LoadAs<float>(bytes, offset, order);
  return LoadAs<double>(bytes, offset, order);
}

uint64_t LoadHeader(absl::string_view bytes, size_t index, const Encoding& enc) {
  const size_t offset = index * enc.header_bytes;
  if (enc.header_bytes == 8) return LoadAs<uint64_t>(bytes, offset, enc.order);
  return LoadAs<uint32_t>(bytes, offset, enc.order);
}

class ArrayDecoder {
 public:
  ArrayDecoder(absl::string_view path, const Encoding& enc) : path_(path), enc_(enc) {}

  // The `count` values of DataArray `array`, as doubles (exact for every integer a mesh uses).
  absl::StatusOr<std::vector<double>> Decode(const XmlElement& array, uint64_t count) {
    const std::string* type = array.Attribute("type");
    if (type == nullptr || TypeSize(*type) == 0) {
      return Error(array, absl::StrCat("has unknown type \"", type ? *type : "", "\""));
    }
    const std::string* format = array.Attribute("format");
    if (format == nullptr || *format == "ascii") return Ascii(array, count);
    if (*format == "binary") return Binary(array, *type, count);
    if (*format == "appended") return Unsupported(array, "uses appended data");
    return Error(array, absl::StrCat("has unknown format \"", *format, "\""));
  }

 private:
  absl::Status Error(const XmlElement& array, absl::string_view problem) {
    const std::string* name = array.Attribute("Name");
    return FileLineError(
        path_, array.line,
        absl::StrCat("DataArray", name ? absl::StrCat(" \"", *name, "\"") : "", " ", problem));
  }
  absl::Status Unsupported(const XmlElement& array, absl::string_view problem) {
    return absl::UnimplementedError(Error(array, problem).message());
  }

  absl::StatusOr<std::vector<double>> Ascii(const XmlElement& array, uint64_t count) {
    const absl::string_view text = array.text;
    // Each value takes at least two characters ("0 ").
    if (count > text.size() / 2 + 1) {
      return Error(array, absl::StrCat("needs ", count, " values but holds only ", text.size(),
                                       " characters (truncated?)"));
    }
    std::vector<double> values;
    values.reserve(count);
    size_t pos = 0;
    while (true) {
      while (pos < text.size() && absl::ascii_isspace(static_cast<unsigned char>(text[pos]))) {
        ++pos;
      }
      if (pos >= text.size()) break;
      size_t end = pos;
      while (end < text.size() && !absl::ascii_isspace(static_cast<unsigned char>(text[end]))) {
        ++end;
      }
      double value;
      if (!ParseDouble(text.substr(pos, end - pos), value)) {
        return Error(array, absl::StrCat("value ", values.size(), " is not a number: \"",
                                         text.substr(pos, std::min<size_t>(end - pos, 30)), "\""));
      }
      if (values.size() == count) {
        return Error(array, absl::StrCat("has more than the expected ", count, " values"));
      }
      values.push_back(value);
      pos = end;
    }
    if (values.size() != count) {
      return Error(array, absl::StrCat("has ", values.size(), " values, expected ", count));
    }
    return values;
  }

  absl::StatusOr<std::vector<double>> Binary(const XmlElement& array, const std::string& type,
                                             uint64_t count) {
    const size_t width = TypeSize(type);
    const uint64_t expected = count * width;
    std::string raw;
    if (!enc_.zlib) {
      absl::StatusOr<std::string> decoded = Base64Decode(array.text);
      if (!decoded.ok()) return Error(array, decoded.status().message());
      if (decoded->size() < enc_.header_bytes) return Error(array, "is truncated");
      const uint64_t nbytes = LoadHeader(*decoded, 0, enc_);
      if (nbytes != expected) {
        return Error(array, absl::StrCat("header says ", nbytes, " bytes, expected ", expected,
                                         " for ", count, " values"));
      }
      if (decoded->size() - enc_.header_bytes < nbytes) {
        return Error(array, absl::StrCat("is truncated: header says ", nbytes, " bytes, has ",
                                         decoded->size() - enc_.header_bytes));
      }
      raw = decoded->substr(enc_.header_bytes, nbytes);
    } else {
      absl::StatusOr<std::string> inflated = Compressed(array, expected);
      if (!inflated.ok()) return inflated.status();
      raw = *std::move(inflated);
    }
    std::vector<double> values(count);
    for (uint64_t i = 0; i < count; ++i) values[i] = LoadValue(raw, i * width, type, enc_.order);
    return values;
  }

  // vtkZLibDataCompressor layout: base64(header) base64(blocks), header = [nblocks, block size,
  // last block size, compressed size of each block].
  absl::StatusOr<std::string> Compressed(const XmlElement& array, uint64_t expected) {
    std::string text;
    for (char c : array.text) {
      if (!absl::ascii_isspace(static_cast<unsigned char>(c))) text.push_back(c);
    }
    const auto chars_for = [](uint64_t bytes) { return (bytes + 2) / 3 * 4; };
    const size_t h = enc_.header_bytes;
    if (text.size() < chars_for(h)) return Error(array, "is truncated");
    absl::StatusOr<std::string> first =
        Base64Decode(absl::string_view(text).substr(0, chars_for(h)));
    if (!first.ok()) return Error(array, first.status().message());
    const uint64_t blocks = LoadHeader(*first, 0, enc_);
    if (blocks > text.size()) return Error(array, "has a corrupt block count");
    const uint64_t header_chars = chars_for((3 + blocks) * h);
    if (text.size() < header_chars) return Error(array, "is truncated in its header");
    absl::StatusOr<std::string> header =
        Base64Decode(absl::string_view(text).substr(0, header_chars));
    if (!header.ok()) return Error(array, header.status().message());
    absl::StatusOr<std::string> data = Base64Decode(absl::string_view(text).substr(header_chars));
    if (!data.ok()) return Error(array, data.status().message());
    const uint64_t block_size = LoadHeader(*header, 1, enc_);
    const uint64_t last_size = LoadHeader(*header, 2, enc_);
    const uint64_t total =
        blocks == 0 ? 0 : (blocks - 1) * block_size + (last_size == 0 ? block_size : last_size);
    if (total != expected) {
      return Error(array, absl::StrCat("header says ", total, " bytes, expected ", expected));
    }
    if (expected / kMaxInflateRatio > data->size()) {
      return Error(array, "claims more data than its compressed size can hold (corrupt)");
    }
    std::string out;
    out.reserve(expected);
    uint64_t offset = 0;
    for (uint64_t b = 0; b < blocks; ++b) {
      const uint64_t csize = LoadHeader(*header, 3 + b, enc_);
      if (csize > data->size() - offset) return Error(array, "is truncated in its data");
      const uint64_t usize = b + 1 == blocks && last_size != 0 ? last_size : block_size;
      absl::StatusOr<std::string> block =
          InflateExact(absl::string_view(*data).substr(offset, csize), usize);
      if (!block.ok()) return Error(array, block.status().message());
      out += *block;
      offset += csize;
    }
    return out;
  }

  absl::string_view path_;
  Encoding enc_;
};

// Appends a binary DataArray: base64 of [UInt64 byte count][little-endian values].
template <typename T>
void AppendArray(std::string& out, absl::string_view attributes, const std::vector<T>& values) {
  std::string raw;
  raw.reserve(8 + values.size() * sizeof(T));
  AppendLittle<uint64_t>(raw, values.size() * sizeof(T));
  for (const T& v : values) AppendLittle(raw, v);
  absl::StrAppend(&out, "        <DataArray ", attributes, " format=\"binary\">\n          ",
                  Base64Encode(raw), "\n        </DataArray>\n");
}

int64_t AttributeInt(const XmlElement& e, absl::string_view key, int64_t fallback) {
  const std::string* value = e.Attribute(key);
  int64_t out;
  if (value == nullptr || !ParseInt64(*value, out)) return fallback;
  return out;
}

}  // namespace

absl::StatusOr<MeshFile> ParseVtu(absl::string_view text, absl::string_view path) {
  if (absl::StrContains(text, "<AppendedData")) {
    return FileUnsupported(path,
                           "appended data (<AppendedData>) is not read; write the .vtu "
                           "with inline ascii or binary arrays");
  }
  absl::StatusOr<XmlElement> root = ParseXml(text, path);
  if (!root.ok()) return root.status();
  if (root->name != "VTKFile") return FileError(path, "root element is not <VTKFile>");
  const std::string* type = root->Attribute("type");
  if (type == nullptr || *type != "UnstructuredGrid") {
    return FileError(
        path, absl::StrCat("VTKFile type \"", type ? *type : "", "\" is not UnstructuredGrid"));
  }
  Encoding enc;
  if (const std::string* order = root->Attribute("byte_order")) {
    if (*order == "BigEndian") {
      enc.order = ByteOrder::kBig;
    } else if (*order != "LittleEndian") {
      return FileError(path, absl::StrCat("unknown byte_order \"", *order, "\""));
    }
  }
  if (const std::string* header_type = root->Attribute("header_type")) {
    if (*header_type == "UInt64") {
      enc.header_bytes = 8;
    } else if (*header_type != "UInt32") {
      return FileError(path, absl::StrCat("unknown header_type \"", *header_type, "\""));
    }
  }
  if (const std::string* compressor = root->Attribute("compressor")) {
    if (*compressor != "vtkZLibDataCompressor") {
      return FileUnsupported(
          path, absl::StrCat("compressor \"", *compressor, "\" is not supported (only zlib)"));
    }
    enc.zlib = true;
  }
  const XmlElement* grid = root->Child("UnstructuredGrid");
  if (grid == nullptr) return FileError(path, "no <UnstructuredGrid>");
  const XmlElement* piece = grid->Child("Piece");
  if (piece == nullptr) return FileError(path, "no <Piece>");
  if (std::count_if(grid->children.begin(), grid->children.end(),
                    [](const XmlElement& e) { return e.name == "Piece"; }) > 1) {
    return FileUnsupported(path, "more than one <Piece> (merge the pieces first)");
  }
  const int64_t v = AttributeInt(*piece, "NumberOfPoints", -1);
  const int64_t n = AttributeInt(*piece, "NumberOfCells", -1);
  if (v < 0 || v > int64_t{0xffffffff} || n < 0 || n > (int64_t{1} << 40)) {
    return FileLineError(path, piece->line, "Piece needs valid NumberOfPoints and NumberOfCells");
  }

  ArrayDecoder decoder(path, enc);
  MeshFile file;
  const XmlElement* points = piece->Child("Points");
  const XmlElement* points_array = points ? points->Child("DataArray") : nullptr;
  if (points_array == nullptr) return FileError(path, "no <Points><DataArray>");
  if (AttributeInt(*points_array, "NumberOfComponents", 1) != 3) {
    return FileLineError(path, points_array->line, "Points DataArray must have 3 components");
  }
  absl::StatusOr<std::vector<double>> xyz = decoder.Decode(*points_array, 3 * v);
  if (!xyz.ok()) return xyz.status();
  file.mesh.points.resize(v);
  for (int64_t i = 0; i < v; ++i) {
    file.mesh.points[i] = {(*xyz)[3 * i], (*xyz)[3 * i + 1], (*xyz)[3 * i + 2]};
  }

  const XmlElement* cells = piece->Child("Cells");
  if (cells == nullptr) return FileError(path, "no <Cells>");
  const XmlElement* arrays[3] = {nullptr, nullptr, nullptr};  // connectivity, offsets, types
  for (const XmlElement& child : cells->children) {
    const std::string* name = child.Attribute("Name");
    if (name == nullptr) continue;
    if (*name == "connectivity") arrays[0] = &child;
    if (*name == "offsets") arrays[1] = &child;
    if (*name == "types") arrays[2] = &child;
  }
  if (arrays[0] == nullptr || arrays[1] == nullptr || arrays[2] == nullptr) {
    return FileLineError(path, cells->line, "Cells needs connectivity, offsets and types arrays");
  }
  // XML offsets are cell ends; VtkCells wants a leading 0.
  absl::StatusOr<std::vector<double>> offsets = decoder.Decode(*arrays[1], n);
  if (!offsets.ok()) return offsets.status();
  absl::StatusOr<std::vector<double>> types = decoder.Decode(*arrays[2], n);
  if (!types.ok()) return types.status();
  const double connectivity_size = n == 0 ? 0.0 : offsets->back();
  if (!(connectivity_size >= 0 &&
        connectivity_size <= static_cast<double>(text.size()) * kMaxInflateRatio)) {
    return FileLineError(path, arrays[1]->line, "last cell offset is out of range");
  }
  absl::StatusOr<std::vector<double>> connectivity =
      decoder.Decode(*arrays[0], static_cast<uint64_t>(connectivity_size));
  if (!connectivity.ok()) return connectivity.status();
  VtkCells vtk;
  vtk.offsets.reserve(n + 1);
  vtk.offsets.push_back(0);
  // Converting a double beyond int64 (or NaN) is undefined; -1 is refused as an offset and
  // ignored as a cell type by CellsToTets.
  auto whole = [](double d) {
    return d >= 0 && d < 0x1p62 && d == std::floor(d) ? static_cast<int64_t>(d) : int64_t{-1};
  };
  for (double o : *offsets) vtk.offsets.push_back(whole(o));
  for (double t : *types) vtk.types.push_back(whole(t));
  vtk.connectivity.reserve(connectivity->size());
  for (double c : *connectivity) {
    // A fractional or huge index is out of range either way; keep it negative to say so.
    vtk.connectivity.push_back(
        c >= 0 && c < 4294967296.0 && c == std::floor(c) ? static_cast<int64_t>(c) : -1);
  }

  VtkCellData cell_data;
  if (const XmlElement* section = piece->Child("CellData")) {
    for (const XmlElement& child : section->children) {
      const std::string* name = child.Attribute("Name");
      if (name == nullptr || AttributeInt(child, "NumberOfComponents", 1) != 1) continue;
      std::vector<double>* out = *name == "iteration" ? &cell_data.iteration
                                 : *name == "quality" ? &cell_data.quality
                                                      : nullptr;
      if (out == nullptr) continue;
      absl::StatusOr<std::vector<double>> values = decoder.Decode(child, n);
      if (!values.ok()) return values.status();
      *out = *std::move(values);
    }
  }
  if (const XmlElement* section = piece->Child("PointData")) {
    for (const XmlElement& child : section->children) {
      const std::string* name = child.Attribute("Name");
      if (name == nullptr || *name != "value" ||
          AttributeInt(child, "NumberOfComponents", 1) != 1) {
        continue;
      }
      absl::StatusOr<std::vector<double>> values = decoder.Decode(child, v);
      if (!values.ok()) return values.status();
      file.mesh.values = *std::move(values);
    }
  }
  int64_t ignored = 0;
  if (absl::Status s = CellsToTets(vtk, cell_data, v, path, file, ignored); !s.ok()) return s;
  if (absl::Status s = ValidateMeshFile(file, path); !s.ok()) return s;
  return file;
}

std::string FormatVtu(const MeshFile& file) {
  const Mesh& mesh = file.mesh;
  const size_t v = mesh.points.size();
  const size_t t = mesh.tets.size();
  std::string out =
      "<?xml version=\"1.0\"?>\n"
      "<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" "
      "header_type=\"UInt64\">\n  <UnstructuredGrid>\n";
  absl::StrAppend(&out, "    <Piece NumberOfPoints=\"", v, "\" NumberOfCells=\"", t, "\">\n");
  if (!mesh.values.empty()) {
    out += "      <PointData Scalars=\"value\">\n";
    AppendArray(out, "type=\"Float64\" Name=\"value\"", mesh.values);
    out += "      </PointData>\n";
  }
  if (!file.tet_iteration.empty() || !file.tet_quality.empty()) {
    out += "      <CellData>\n";
    if (!file.tet_iteration.empty()) {
      AppendArray(out, "type=\"Int32\" Name=\"iteration\"", file.tet_iteration);
    }
    if (!file.tet_quality.empty()) {
      AppendArray(out, "type=\"Float32\" Name=\"quality\"", file.tet_quality);
    }
    out += "      </CellData>\n";
  }
  std::vector<double> xyz;
  xyz.reserve(3 * v);
  for (const Vec3& p : mesh.points) xyz.insert(xyz.end(), p.begin(), p.end());
  out += "      <Points>\n";
  AppendArray(out, "type=\"Float64\" Name=\"Points\" NumberOfComponents=\"3\"", xyz);
  out += "      </Points>\n      <Cells>\n";
  std::vector<int64_t> connectivity;
  connectivity.reserve(4 * t);
  for (const Tet& tet : mesh.tets) connectivity.insert(connectivity.end(), tet.begin(), tet.end());
  AppendArray(out, "type=\"Int64\" Name=\"connectivity\"", connectivity);
  std::vector<int64_t> offsets(t);
  for (size_t i = 0; i < t; ++i) offsets[i] = 4 * static_cast<int64_t>(i + 1);
  AppendArray(out, "type=\"Int64\" Name=\"offsets\"", offsets);
  AppendArray(out, "type=\"UInt8\" Name=\"types\"", std::vector<uint8_t>(t, kVtkTetra));
  out += "      </Cells>\n    </Piece>\n  </UnstructuredGrid>\n</VTKFile>\n";
  return out;
}

}  // namespace tetrefine::io
