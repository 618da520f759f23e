// Writing VTK XML unstructured grids (.vtu). See vtu_format.h for the layout.
#include <tbb/parallel_for.h>

#include <cstring>
#include <limits>
#include <string>
#include <vector>

#include "absl/strings/str_cat.h"
#include "client/io/base64.h"
#include "client/io/byte_order.h"
#include "client/io/mesh_frame.h"
#include "client/io/number_text.h"
#include "client/io/vtk_cells.h"
#include "client/io/vtk_scalar.h"
#include "client/io/vtu_format.h"

namespace tetrefine::io {
namespace {

// zlib level 1 when the caller does not choose. Measured on a refined 1.6 M-tet mesh (value,
// iteration, quality and label arrays; bench/file_formats.sh): level 1 gives 21.5 bytes per tet
// at about 5x the speed of level 6 (20.2 bytes per tet), whose extra 6% saving is not worth it.
constexpr int kDefaultZlibLevel = 1;
constexpr int kDefaultLzmaLevel = 1;

// One array to write: where it goes, its XML attributes and its little-endian bytes.
struct OutArray {
  std::string element;     // "DataArray" or "Array" (field data)
  std::string attributes;  // type, Name, NumberOfComponents / NumberOfTuples
  VtkScalar type = VtkScalar::kUInt8;
  bool is_string = false;  // a String array: raw holds NUL-terminated strings
  std::string raw;
  std::string encoded;  // header + data, compressed when asked
};

template <typename T>
std::string LittleBytes(const T* values, size_t n) {
  std::string raw(n * sizeof(T), '\0');
  if (kNativeOrder == ByteOrder::kLittle) {
    if (n > 0) std::memcpy(raw.data(), values, n * sizeof(T));
  } else {
    raw.clear();
    for (size_t i = 0; i < n; ++i) AppendLittle(raw, values[i]);
  }
  return raw;
}

std::string EscapeXml(absl::string_view text) {
  std::string out;
  for (char c : text) {
    switch (c) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      default:
        out.push_back(c);
    }
  }
  return out;
}

template <typename T>
OutArray Numeric(absl::string_view name, VtkScalar type, int components, const T* values,
                 size_t n) {
  OutArray a;
  a.element = "DataArray";
  a.type = type;
  a.attributes =
      absl::StrCat("type=\"", VtkScalarXmlName(type), "\" Name=\"", EscapeXml(name), "\"");
  if (components != 1) absl::StrAppend(&a.attributes, " NumberOfComponents=\"", components, "\"");
  a.raw = LittleBytes(values, n);
  return a;
}

void AppendHeaderWord(std::string& out, uint64_t word) { AppendLittle<uint64_t>(out, word); }

// Encodes every array's bytes (header + data) as the options say, compressing all blocks of all
// arrays in parallel.
void EncodeAll(std::vector<OutArray>& arrays, const VtuWriteOptions& options) {
  const VtkCompressor compressor = options.compressor;
  if (compressor == VtkCompressor::kNone) {
    for (OutArray& a : arrays) {
      a.encoded.reserve(8 + a.raw.size());
      AppendHeaderWord(a.encoded, a.raw.size());
      a.encoded += a.raw;
    }
    return;
  }
  int level = options.level;
  if (level < 0) level = compressor == VtkCompressor::kLzma ? kDefaultLzmaLevel : kDefaultZlibLevel;
  const size_t block = std::max<size_t>(options.block_size, 1);
  struct Job {
    size_t array;
    size_t begin;
    size_t size;
  };
  std::vector<Job> jobs;
  for (size_t a = 0; a < arrays.size(); ++a) {
    for (size_t begin = 0; begin < arrays[a].raw.size(); begin += block) {
      jobs.push_back({a, begin, std::min(block, arrays[a].raw.size() - begin)});
    }
  }
  std::vector<std::string> compressed(jobs.size());
  tbb::parallel_for(size_t{0}, jobs.size(), [&](size_t j) {
    const Job& job = jobs[j];
    CompressBlock(compressor, level,
                  absl::string_view(arrays[job.array].raw).substr(job.begin, job.size),
                  compressed[j]);
  });
  size_t j = 0;
  for (OutArray& a : arrays) {
    const size_t blocks = (a.raw.size() + block - 1) / block;
    AppendHeaderWord(a.encoded, blocks);
    AppendHeaderWord(a.encoded, block);
    AppendHeaderWord(a.encoded, a.raw.size() % block);
    size_t total = 0;
    for (size_t b = 0; b < blocks; ++b) {
      AppendHeaderWord(a.encoded, compressed[j + b].size());
      total += compressed[j + b].size();
    }
    a.encoded.reserve(a.encoded.size() + total);
    for (size_t b = 0; b < blocks; ++b) a.encoded += compressed[j + b];
    j += blocks;
  }
}

// VTK encodes a compressed array's header and its blocks as two base64 runs.
std::string InlineBase64(const OutArray& a, const VtuWriteOptions& options) {
  if (options.compressor == VtkCompressor::kNone) return Base64Encode(a.encoded);
  const size_t blocks = LoadAs<uint64_t>(a.encoded, 0, ByteOrder::kLittle);
  const size_t header = 8 * (3 + blocks);
  return absl::StrCat(Base64Encode(absl::string_view(a.encoded).substr(0, header)),
                      Base64Encode(absl::string_view(a.encoded).substr(header)));
}

void AppendAsciiValues(std::string& out, const OutArray& a) {
  if (a.is_string) {
    for (char c : a.raw)
      absl::StrAppend(&out, static_cast<int>(static_cast<unsigned char>(c)), " ");
    return;
  }
  const size_t width = VtkScalarSize(a.type);
  const size_t n = a.raw.size() / width;
  for (size_t i = 0; i < n; ++i) {
    if (i > 0) out.push_back(i % 6 == 0 ? '\n' : ' ');
    switch (a.type) {
      case VtkScalar::kFloat64:
        AppendDouble(out, LoadAs<double>(a.raw, i * 8, ByteOrder::kLittle));
        break;
      case VtkScalar::kFloat32:
        AppendFloat(out, LoadAs<float>(a.raw, i * 4, ByteOrder::kLittle));
        break;
      default: {
        int64_t value;
        ScalarsToInt64s(a.raw.substr(i * width, width), a.type, ByteOrder::kLittle, 1, &value);
        absl::StrAppend(&out, value);
      }
    }
  }
}

// Writes one array element; appended arrays take their offset into the appended section.
void AppendArrayXml(std::string& out, const OutArray& a, const VtuWriteOptions& options,
                    absl::string_view indent, size_t& appended_offset) {
  absl::StrAppend(&out, indent, "<", a.element, " ", a.attributes);
  switch (options.layout) {
    case VtuWriteOptions::Layout::kAppendedRaw:
      absl::StrAppend(&out, " format=\"appended\" offset=\"", appended_offset, "\"/>\n");
      appended_offset += a.encoded.size();
      return;
    case VtuWriteOptions::Layout::kInlineBase64:
      absl::StrAppend(&out, " format=\"binary\">\n", indent, "  ", InlineBase64(a, options), "\n");
      break;
    case VtuWriteOptions::Layout::kAscii:
      absl::StrAppend(&out, " format=\"ascii\">\n");
      AppendAsciiValues(out, a);
      out += "\n";
      break;
  }
  absl::StrAppend(&out, indent, "</", a.element, ">\n");
}

}  // namespace

std::string FormatVtu(const MeshFile& file, const VtuWriteOptions& options) {
  const Mesh& mesh = file.mesh;
  const size_t v = mesh.points.size();
  const size_t t = mesh.tets.size();
  const bool ascii = options.layout == VtuWriteOptions::Layout::kAscii;

  std::vector<OutArray> arrays;
  // Order of the sections below: field data, point data, cell data, points, cells.
  size_t field = 0, point_data = 0, cell_data = 0;
  if (file.frame != MeshFrame::kUntagged) {
    OutArray a;
    a.element = "Array";
    a.attributes = "type=\"String\" Name=\"SPACE\" NumberOfTuples=\"1\"";
    a.is_string = true;
    a.raw = absl::StrCat(FrameTag(file.frame), std::string(1, '\0'));
    arrays.push_back(std::move(a));
    ++field;
  }
  if (!mesh.values.empty()) {
    arrays.push_back(Numeric("value", VtkScalar::kFloat64, 1, mesh.values.data(), v));
    ++point_data;
  }
  if (!file.tet_iteration.empty()) {
    arrays.push_back(Numeric("iteration", VtkScalar::kInt32, 1, file.tet_iteration.data(), t));
    ++cell_data;
  }
  if (!file.tet_quality.empty()) {
    arrays.push_back(Numeric("quality", VtkScalar::kFloat32, 1, file.tet_quality.data(), t));
    ++cell_data;
  }
  if (!file.mesh.labels.empty()) {
    arrays.push_back(
        Numeric(LabelArrayName(file), VtkScalar::kInt32, 1, file.mesh.labels.data(), t));
    ++cell_data;
  }
  {
    std::vector<double> xyz(3 * v);
    const double sx = FrameSign(file.frame, 0);
    const double sy = FrameSign(file.frame, 1);
    for (size_t i = 0; i < v; ++i) {
      xyz[3 * i] = sx * mesh.points[i][0];
      xyz[3 * i + 1] = sy * mesh.points[i][1];
      xyz[3 * i + 2] = mesh.points[i][2];
    }
    arrays.push_back(Numeric("Points", VtkScalar::kFloat64, 3, xyz.data(), 3 * v));
  }
  // 32-bit indices halve the largest array; VTK, ParaView and meshio read any integer type.
  const bool small_indices = v <= static_cast<size_t>(std::numeric_limits<int32_t>::max());
  const bool small_offsets = 4 * t <= static_cast<size_t>(std::numeric_limits<int32_t>::max());
  if (small_indices) {
    static_assert(sizeof(Tet) == 4 * sizeof(uint32_t));
    const uint32_t* flat = t == 0 ? nullptr : mesh.tets[0].data();
    arrays.push_back(Numeric("connectivity", VtkScalar::kInt32, 1,
                             reinterpret_cast<const int32_t*>(flat), 4 * t));
  } else {
    std::vector<int64_t> flat(4 * t);
    for (size_t i = 0; i < t; ++i) {
      for (int k = 0; k < 4; ++k) flat[4 * i + k] = mesh.tets[i][k];
    }
    arrays.push_back(Numeric("connectivity", VtkScalar::kInt64, 1, flat.data(), 4 * t));
  }
  if (small_offsets) {
    std::vector<int32_t> offsets(t);
    for (size_t i = 0; i < t; ++i) offsets[i] = static_cast<int32_t>(4 * (i + 1));
    arrays.push_back(Numeric("offsets", VtkScalar::kInt32, 1, offsets.data(), t));
  } else {
    std::vector<int64_t> offsets(t);
    for (size_t i = 0; i < t; ++i) offsets[i] = static_cast<int64_t>(4 * (i + 1));
    arrays.push_back(Numeric("offsets", VtkScalar::kInt64, 1, offsets.data(), t));
  }
  {
    const std::vector<uint8_t> types(t, kVtkTetra);
    arrays.push_back(Numeric("types", VtkScalar::kUInt8, 1, types.data(), t));
  }
  if (!ascii) EncodeAll(arrays, options);

  std::string out =
      "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" "
      "byte_order=\"LittleEndian\" header_type=\"UInt64\"";
  if (!ascii && options.compressor != VtkCompressor::kNone) {
    absl::StrAppend(&out, " compressor=\"", VtkCompressorName(options.compressor), "\"");
  }
  out += ">\n  <UnstructuredGrid>\n";
  size_t offset = 0;
  size_t next = 0;
  const auto section = [&](absl::string_view open, absl::string_view close, size_t count,
                           absl::string_view indent) {
    if (count == 0) return;
    absl::StrAppend(&out, open);
    for (size_t i = 0; i < count; ++i) AppendArrayXml(out, arrays[next++], options, indent, offset);
    absl::StrAppend(&out, close);
  };
  section("    <FieldData>\n", "    </FieldData>\n", field, "      ");
  absl::StrAppend(&out, "    <Piece NumberOfPoints=\"", v, "\" NumberOfCells=\"", t, "\">\n");
  section("      <PointData Scalars=\"value\">\n", "      </PointData>\n", point_data, "        ");
  section("      <CellData>\n", "      </CellData>\n", cell_data, "        ");
  section("      <Points>\n", "      </Points>\n", 1, "        ");
  section("      <Cells>\n", "      </Cells>\n", 3, "        ");
  out += "    </Piece>\n  </UnstructuredGrid>\n";
  if (options.layout == VtuWriteOptions::Layout::kAppendedRaw) {
    out.reserve(out.size() + offset + 64);
    out += "  <AppendedData encoding=\"raw\">\n   _";
    for (const OutArray& a : arrays) out += a.encoded;
    out += "\n  </AppendedData>\n";
  }
  out += "</VTKFile>\n";
  return out;
}

}  // namespace tetrefine::io
