// Writing VTK XML unstructured grids (.vtu). See vtu_format.h for the layout.
#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cstring>
#include <limits>
#include <memory>
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
#include "client/io/xml_escape.h"
#include "core/huge_pages.h"

namespace tetrefine::io {
namespace {

// zlib's coder when the caller does not choose: libdeflate's level 1, whose bytes depend only on
// the data. ISA-L's igzip (kFastestZlibLevel) encodes faster but wrote different bytes for the
// same mesh from one run to another (a sweep found it on 2026-11-27: 3 different files in 10
// identical runs; traced to igzip itself, see vtk_compressor.h), and a pipeline that checksums or
// caches its outputs needs the same bytes for the same mesh. What it costs, bench/mesh_io_bench on
// bench/file_to_file.sh's output (2.81 M tets, 2 threads, both coders in one run, 2026-11-27):
// encode 0.217 s against ISA-L's 0.127 s, write 0.267 s against 0.156 s, 15.16 bytes per tet
// against 15.44. Measured before (2026-11-25): zlib's own deflate writes 15.2 bytes per tet at
// level 1 at 2.3x libdeflate's time, and libdeflate's level 6 16.1 at 1.8x; the file is well under
// the 25 bytes per tet aimed at either way.
constexpr int kDefaultZlibLevel = 1;
constexpr int kDefaultLzmaLevel = 1;

// One array to write: where it goes, its XML attributes, its little-endian bytes (a view of the
// mesh's own memory when the host is little-endian, or of `owned`) and, once compressed, its
// blocks.
struct OutArray {
  std::string element;     // "DataArray" or "Array" (field data)
  std::string attributes;  // type, Name, NumberOfComponents / NumberOfTuples
  VtkScalar type = VtkScalar::kUInt8;
  bool is_string = false;  // a String array: raw holds NUL-terminated strings
  std::string owned;
  absl::string_view raw;
  std::vector<std::string> blocks;  // compressed blocks (compressed files only)

  // Header plus data as stored in the file.
  uint64_t EncodedSize(bool compressed) const {
    if (!compressed) return 8 + raw.size();
    uint64_t size = 8 * (3 + blocks.size());
    for (const std::string& b : blocks) size += b.size();
    return size;
  }
};

template <typename T>
void SetRaw(OutArray& a, const T* values, size_t n) {
  if (kNativeOrder == ByteOrder::kLittle) {
    a.raw = n == 0 ? absl::string_view()
                   : absl::string_view(reinterpret_cast<const char*>(values), n * sizeof(T));
    return;
  }
  a.owned.clear();
  for (size_t i = 0; i < n; ++i) AppendLittle(a.owned, values[i]);
  a.raw = a.owned;
}

template <typename T>
void SetOwned(OutArray& a, const std::vector<T>& values) {
  a.owned.clear();
  if (kNativeOrder == ByteOrder::kLittle) {
    ReserveHuge(a.owned, values.size() * sizeof(T));
    a.owned.resize(values.size() * sizeof(T));
    if (!values.empty()) std::memcpy(a.owned.data(), values.data(), a.owned.size());
  } else {
    for (const T& v : values) AppendLittle(a.owned, v);
  }
  a.raw = a.owned;
}

OutArray Numeric(absl::string_view name, VtkScalar type, int components) {
  OutArray a;
  a.element = "DataArray";
  a.type = type;
  a.attributes =
      absl::StrCat("type=\"", VtkScalarXmlName(type), "\" Name=\"", EscapeXml(name), "\"");
  if (components != 1) absl::StrAppend(&a.attributes, " NumberOfComponents=\"", components, "\"");
  return a;
}

void AppendHeaderWord(std::string& out, uint64_t word) { AppendLittle<uint64_t>(out, word); }

size_t BlockSize(const VtuWriteOptions& options) { return std::max<size_t>(options.block_size, 1); }

// Compresses every block of every array in parallel, one coder per task range.
void CompressAll(std::vector<OutArray>& arrays, const VtuWriteOptions& options) {
  int level = options.level;
  if (level < 0) {
    level = options.compressor == VtkCompressor::kLzma ? kDefaultLzmaLevel : kDefaultZlibLevel;
  }
  const size_t block = BlockSize(options);
  struct Job {
    OutArray* array;
    size_t index;
  };
  std::vector<Job> jobs;
  for (OutArray& a : arrays) {
    a.blocks.resize((a.raw.size() + block - 1) / block);
    for (size_t b = 0; b < a.blocks.size(); ++b) jobs.push_back({&a, b});
  }
  // One coder per thread: a coder per task range made 181 of them for the 3,312 blocks of
  // bench/file_to_file.sh's output, and ISA-L's holds 365 KB of fresh memory.
  tbb::enumerable_thread_specific<std::unique_ptr<BlockCompressor>> coders;
  tbb::parallel_for(tbb::blocked_range<size_t>(0, jobs.size(), 4),
                    [&](const tbb::blocked_range<size_t>& range) {
                      std::unique_ptr<BlockCompressor>& coder = coders.local();
                      if (coder == nullptr) {
                        coder = std::make_unique<BlockCompressor>(options.compressor, level);
                      }
                      for (size_t j = range.begin(); j != range.end(); ++j) {
                        const Job& job = jobs[j];
                        coder->Compress(job.array->raw.substr(job.index * block, block),
                                        job.array->blocks[job.index]);
                      }
                    });
}

// meshio (5.0, Debian 12's; the code is unchanged in later releases) reads a compressed
// appended .vtu by decoding the arrays in file order and renumbering each one's offset to where
// it lands in the base64 text it builds, looking each next array up by its original offset.
// When a renumbered offset (a base64 length, a multiple of 4) equals a later array's original
// offset, it takes the wrong array: a sweep found 1 of 885 refined meshes unreadable ("cannot
// reshape array of size 30 into shape (90,3)"); two arrays of one size would be swapped
// silently. A zlib stream may hold empty stored blocks (the 5 bytes Z_SYNC_FLUSH writes; every
// inflater skips them): one goes after the zlib header of an array's first block wherever the
// next array's offset would be a multiple of 4, so that no offset but the first is. The data
// decoded is the same.
void KeepOffsetsOffMultiplesOfFour(std::vector<OutArray>& arrays) {
  static constexpr char kEmptyStoredBlock[] = {0x00, 0x00, 0x00, static_cast<char>(0xFF),
                                               static_cast<char>(0xFF)};
  uint64_t offset = 0;
  for (size_t k = 0; k + 1 < arrays.size(); ++k) {
    OutArray& a = arrays[k];
    offset += a.EncodedSize(/*compressed=*/true);
    // A zlib stream starts with a 2-byte header (libdeflate sets no preset dictionary).
    if (offset % 4 != 0 || a.blocks.empty() || a.blocks.front().size() < 2) continue;
    a.blocks.front().insert(2, kEmptyStoredBlock, sizeof(kEmptyStoredBlock));
    offset += sizeof(kEmptyStoredBlock);
  }
}

// Appends an array's header and data as stored in the file.
void AppendEncoded(std::string& out, const OutArray& a, bool compressed, size_t block) {
  if (!compressed) {
    AppendHeaderWord(out, a.raw.size());
    out.append(a.raw.data(), a.raw.size());
    return;
  }
  AppendHeaderWord(out, a.blocks.size());
  AppendHeaderWord(out, block);
  AppendHeaderWord(out, a.raw.size() % block);
  for (const std::string& b : a.blocks) AppendHeaderWord(out, b.size());
  for (const std::string& b : a.blocks) out += b;
}

// VTK encodes a compressed array's header and its blocks as two base64 runs.
std::string InlineBase64(const OutArray& a, bool compressed, size_t block) {
  std::string encoded;
  AppendEncoded(encoded, a, compressed, block);
  if (!compressed) return Base64Encode(encoded);
  const size_t header = 8 * (3 + a.blocks.size());
  return absl::StrCat(Base64Encode(absl::string_view(encoded).substr(0, header)),
                      Base64Encode(absl::string_view(encoded).substr(header)));
}

void AppendAsciiValues(std::string& out, const OutArray& a) {
  if (a.is_string) {
    for (char c : a.raw) {
      absl::StrAppend(&out, static_cast<int>(static_cast<unsigned char>(c)), " ");
    }
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

}  // namespace

std::string FormatVtu(const MeshFile& file, const VtuWriteOptions& options) {
  const Mesh& mesh = file.mesh;
  const size_t v = mesh.points.size();
  const size_t t = mesh.tets.size();
  using Layout = VtuWriteOptions::Layout;
  const bool compressed =
      options.layout != Layout::kAscii && options.compressor != VtkCompressor::kNone;
  const size_t block = BlockSize(options);

  std::vector<OutArray> arrays;
  arrays.reserve(10);  // views of `owned` strings must not move
  // In the order of the sections below: field data, point data, cell data, points, cells.
  size_t field = 0, point_data = 0, cell_data = 0;
  if (file.frame != MeshFrame::kUntagged) {
    OutArray& a = arrays.emplace_back();
    a.element = "Array";
    a.attributes = "type=\"String\" Name=\"SPACE\" NumberOfTuples=\"1\"";
    a.is_string = true;
    a.owned = absl::StrCat(FrameTag(file.frame), std::string(1, '\0'));
    a.raw = a.owned;
    ++field;
  }
  if (!mesh.values.empty()) {
    SetRaw(arrays.emplace_back(Numeric("value", VtkScalar::kFloat64, 1)), mesh.values.data(), v);
    ++point_data;
  }
  if (!file.tet_iteration.empty()) {
    SetRaw(arrays.emplace_back(Numeric("iteration", VtkScalar::kInt32, 1)),
           file.tet_iteration.data(), t);
    ++cell_data;
  }
  if (!file.tet_quality.empty()) {
    SetRaw(arrays.emplace_back(Numeric("quality", VtkScalar::kFloat32, 1)), file.tet_quality.data(),
           t);
    ++cell_data;
  }
  if (!file.mesh.labels.empty()) {
    SetRaw(arrays.emplace_back(Numeric(LabelArrayName(file), VtkScalar::kInt32, 1)),
           file.mesh.labels.data(), t);
    ++cell_data;
  }
  {
    OutArray& a = arrays.emplace_back(Numeric("Points", VtkScalar::kFloat64, 3));
    static_assert(sizeof(Vec3) == 3 * sizeof(double));
    if (file.frame == MeshFrame::kLps) {
      std::vector<double> xyz(3 * v);
      for (size_t i = 0; i < v; ++i) {
        for (int k = 0; k < 3; ++k) xyz[3 * i + k] = FrameSign(file.frame, k) * mesh.points[i][k];
      }
      SetOwned(a, xyz);
    } else {
      SetRaw(a, v == 0 ? nullptr : mesh.points[0].data(), 3 * v);
    }
  }
  // 32-bit indices halve the largest array; VTK, ParaView and meshio read any integer type.
  if (v <= static_cast<size_t>(std::numeric_limits<int32_t>::max())) {
    static_assert(sizeof(Tet) == 4 * sizeof(uint32_t));
    SetRaw(arrays.emplace_back(Numeric("connectivity", VtkScalar::kInt32, 1)),
           t == 0 ? nullptr : reinterpret_cast<const int32_t*>(mesh.tets[0].data()), 4 * t);
  } else {
    std::vector<int64_t> flat(4 * t);
    for (size_t i = 0; i < t; ++i) {
      for (int k = 0; k < 4; ++k) flat[4 * i + k] = mesh.tets[i][k];
    }
    SetOwned(arrays.emplace_back(Numeric("connectivity", VtkScalar::kInt64, 1)), flat);
  }
  if (4 * t <= static_cast<size_t>(std::numeric_limits<int32_t>::max())) {
    OutArray& a = arrays.emplace_back(Numeric("offsets", VtkScalar::kInt32, 1));
    ReserveHuge(a.owned, 4 * t);
    a.owned.resize(4 * t);
    for (size_t i = 0; i < t; ++i) {
      const uint32_t end = static_cast<uint32_t>(4 * (i + 1));
      const char bytes[4] = {static_cast<char>(end), static_cast<char>(end >> 8),
                             static_cast<char>(end >> 16), static_cast<char>(end >> 24)};
      std::memcpy(a.owned.data() + 4 * i, bytes, 4);
    }
    a.raw = a.owned;
  } else {
    std::vector<int64_t> offsets(t);
    for (size_t i = 0; i < t; ++i) offsets[i] = static_cast<int64_t>(4 * (i + 1));
    SetOwned(arrays.emplace_back(Numeric("offsets", VtkScalar::kInt64, 1)), offsets);
  }
  {
    OutArray& a = arrays.emplace_back(Numeric("types", VtkScalar::kUInt8, 1));
    a.owned.assign(t, static_cast<char>(kVtkTetra));
    a.raw = a.owned;
  }
  if (compressed) CompressAll(arrays, options);
  if (compressed && options.layout == Layout::kAppendedRaw &&
      options.compressor == VtkCompressor::kZlib) {
    KeepOffsetsOffMultiplesOfFour(arrays);
  }

  std::string out =
      "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" "
      "byte_order=\"LittleEndian\" header_type=\"UInt64\"";
  if (compressed) {
    absl::StrAppend(&out, " compressor=\"", VtkCompressorName(options.compressor), "\"");
  }
  out += ">\n  <UnstructuredGrid>\n";
  uint64_t offset = 0;  // of the next array in the appended section
  size_t next = 0;
  const auto section = [&](absl::string_view open, absl::string_view close, size_t count,
                           absl::string_view indent) {
    if (count == 0) return;
    absl::StrAppend(&out, open);
    for (size_t i = 0; i < count; ++i) {
      const OutArray& a = arrays[next++];
      absl::StrAppend(&out, indent, "<", a.element, " ", a.attributes);
      switch (options.layout) {
        case Layout::kAppendedRaw:
          absl::StrAppend(&out, " format=\"appended\" offset=\"", offset, "\"/>\n");
          offset += a.EncodedSize(compressed);
          continue;
        case Layout::kInlineBase64:
          absl::StrAppend(&out, " format=\"binary\">\n", indent, "  ",
                          InlineBase64(a, compressed, block), "\n");
          break;
        case Layout::kAscii:
          out += " format=\"ascii\">\n";
          AppendAsciiValues(out, a);
          out += "\n";
          break;
      }
      absl::StrAppend(&out, indent, "</", a.element, ">\n");
    }
    absl::StrAppend(&out, close);
  };
  section("    <FieldData>\n", "    </FieldData>\n", field, "      ");
  absl::StrAppend(&out, "    <Piece NumberOfPoints=\"", v, "\" NumberOfCells=\"", t, "\">\n");
  section("      <PointData Scalars=\"value\">\n", "      </PointData>\n", point_data, "        ");
  section("      <CellData>\n", "      </CellData>\n", cell_data, "        ");
  section("      <Points>\n", "      </Points>\n", 1, "        ");
  section("      <Cells>\n", "      </Cells>\n", 3, "        ");
  out += "    </Piece>\n  </UnstructuredGrid>\n";
  if (options.layout == Layout::kAppendedRaw) {
    // Reserved to the byte: 2 bytes short (a guess of 64 for these 66) made the last append
    // copy the whole file into a new, doubled buffer whose small pages all faulted in: 0.12 s
    // of the 0.55 s that writing bench/file_to_file.sh's 42 MB output took (2026-11-29).
    constexpr std::string_view kOpen = "  <AppendedData encoding=\"raw\">\n   _";
    constexpr std::string_view kClose = "\n  </AppendedData>\n</VTKFile>\n";
    ReserveHuge(out, out.size() + kOpen.size() + offset + kClose.size());
    out += kOpen;
    for (const OutArray& a : arrays) AppendEncoded(out, a, compressed, block);
    out += kClose;
    return out;
  }
  out += "</VTKFile>\n";
  return out;
}

}  // namespace tetrefine::io
