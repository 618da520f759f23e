// Reading VTK XML images (.vti) with pugixml. See vti_reader.h for what is read.
#include "client/io/vti_reader.h"

#include <array>
#include <cmath>
#include <cstring>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_split.h"
#include "client/io/byte_order.h"
#include "client/io/file_bytes.h"
#include "client/io/grid_placement.h"
#include "client/io/io_error.h"
#include "client/io/number_text.h"
#include "client/io/voxel_decode.h"
#include "client/io/vtk_scalar.h"
#include "client/io/vtk_xml_file.h"
#include "client/io/vtu_data_array.h"
#include "client/io/world_frame.h"

namespace tetrefine::io {
namespace {

using Extent = std::array<int64_t, 6>;  // x0 x1 y0 y1 z0 z1, inclusive sample indices

// Whitespace-separated numbers of attribute `key` of `node`: exactly `n` of them, finite.
absl::StatusOr<std::vector<double>> Numbers(const VtkXmlFile& xml, absl::string_view path,
                                            pugi::xml_node node, const char* key, size_t n) {
  std::vector<double> out;
  for (absl::string_view word :
       absl::StrSplit(node.attribute(key).value(), absl::ByAnyChar(" \t\r\n"), absl::SkipEmpty())) {
    double value;
    if (!ParseDouble(word, value) || !std::isfinite(value)) {
      return FileLineError(path, xml.LineOf(node),
                           absl::StrCat(node.name(), " ", key, ": \"", word.substr(0, 30),
                                        "\" is not a finite number"));
    }
    out.push_back(value);
  }
  if (out.size() != n) {
    return FileLineError(
        path, xml.LineOf(node),
        absl::StrCat(node.name(), " ", key, " has ", out.size(), " numbers, expected ", n));
  }
  return out;
}

absl::StatusOr<Extent> ReadExtent(const VtkXmlFile& xml, absl::string_view path,
                                  pugi::xml_node node, const char* key) {
  Extent extent{};
  size_t n = 0;
  for (absl::string_view word :
       absl::StrSplit(node.attribute(key).value(), absl::ByAnyChar(" \t\r\n"), absl::SkipEmpty())) {
    int64_t value;
    // Indices beyond +-2^40 are corrupt: no axis holds more than 2^20 samples.
    if (n == 6 || !ParseInt64(word, value) || std::abs(value) > (int64_t{1} << 40)) {
      return FileLineError(
          path, xml.LineOf(node),
          absl::StrCat(node.name(), " ", key, " needs 6 integers x0 x1 y0 y1 z0 z1"));
    }
    extent[n++] = value;
  }
  if (n != 6) {
    return FileLineError(
        path, xml.LineOf(node),
        absl::StrCat(node.name(), " ", key, " needs 6 integers x0 x1 y0 y1 z0 z1"));
  }
  return extent;
}

int64_t ComponentCount(pugi::xml_node array) {
  int64_t n = 1;
  if (array.attribute("NumberOfComponents") &&
      !ParseInt64(array.attribute("NumberOfComponents").value(), n)) {
    return -1;
  }
  return n;
}

// The point data array that holds the samples: the one <PointData Scalars="..."> names, else the
// first with one component.
absl::StatusOr<pugi::xml_node> SampleArray(const VtkXmlFile& xml, absl::string_view path,
                                           pugi::xml_node piece) {
  const pugi::xml_node point_data = piece.child("PointData");
  const absl::string_view active = point_data.attribute("Scalars").value();
  pugi::xml_node first_vector;
  for (pugi::xml_node array : point_data.children("DataArray")) {
    const absl::string_view name = array.attribute("Name").value();
    if (!active.empty() && name != active) continue;
    if (ComponentCount(array) == 1) return array;
    if (!first_vector) first_vector = array;
  }
  if (first_vector) {
    return FileLineError(
        path, xml.LineOf(first_vector),
        absl::StrCat("PointData \"", first_vector.attribute("Name").value(), "\" has ",
                     first_vector.attribute("NumberOfComponents").value(),
                     " components: a volume needs one value per sample"));
  }
  if (!active.empty()) {
    return FileLineError(path, xml.LineOf(point_data),
                         absl::StrCat("PointData names Scalars \"", active.substr(0, 40),
                                      "\" but holds no such array"));
  }
  if (const pugi::xml_node cell = piece.child("CellData").child("DataArray")) {
    return FileLineError(
        path, xml.LineOf(cell),
        absl::StrCat("the image holds only cell data (CellData \"", cell.attribute("Name").value(),
                     "\"): tetrefine samples point data, the values at the "
                     "grid's points (ParaView: Cell Data to Point Data)"));
  }
  return FileLineError(path, xml.LineOf(piece), "Piece has no PointData array: no samples");
}

// One piece's samples as stored: little-endian values of `type`, x fastest. The widening of
// types a Volume lacks (DecodeVoxels) waits for the whole image, since whether uint32, int64 or
// uint64 samples become int32 or float64 depends on all of them.
struct PieceSamples {
  StoredType type = StoredType::kFloat64;
  std::string data;
};

absl::StatusOr<PieceSamples> ReadSamples(const VtkXmlFile& xml, VtuArrayReader& arrays,
                                         pugi::xml_node array, uint64_t count) {
  const std::optional<VtkScalar> type = VtkScalarFromXml(array.attribute("type").value());
  if (!type) {
    return arrays.Error(array, absl::StrCat("has type \"", array.attribute("type").value(),
                                            "\", expected a numeric type"));
  }
  PieceSamples out;
  const absl::string_view format = array.attribute("format").value();
  if ((format.empty() || format == "ascii") &&
      (*type == VtkScalar::kInt64 || *type == VtkScalar::kUInt64)) {
    // Text 64-bit integers are read exactly and widen as the binary ones do: read as doubles,
    // -9007199254740993 became -9007199254740992 without a word (an outside review, 2026-11-28),
    // where the same samples stored in binary are refused.
    absl::StatusOr<std::vector<int64_t>> values = arrays.Int64s(array, count);
    if (!values.ok()) return values.status();
    out.type = StoredType::kInt64;
    out.data.reserve(count * sizeof(int64_t));
    for (int64_t v : *values) AppendLittle(out.data, v);
    return out;
  }
  if (format.empty() || format == "ascii") {
    absl::StatusOr<std::vector<double>> values = arrays.Doubles(array, count);
    if (!values.ok()) return values.status();
    out.type = StoredType::kFloat64;
    out.data.reserve(count * sizeof(double));
    for (double v : *values) AppendLittle(out.data, v);
    return out;
  }
  absl::StatusOr<std::string> bytes = arrays.StoredBytes(array, *type, count);
  if (!bytes.ok()) return bytes.status();
  out.type = StoredTypeOfVtk(*type);
  out.data = *std::move(bytes);
  if (xml.encoding.order != ByteOrder::kLittle) {
    SwapEachElement(reinterpret_cast<std::byte*>(out.data.data()), out.data.size(),
                    StoredSize(out.type));
  }
  return out;
}

// The samples of a whole image, in storage order, as a Volume holds them.
absl::StatusOr<DecodedVoxels> Widen(absl::string_view path, StoredType type,
                                    absl::string_view samples) {
  absl::StatusOr<DecodedVoxels> voxels = DecodeVoxels(samples, type, ByteOrder::kLittle, 0, 0);
  if (!voxels.ok()) return WithPath(path, voxels.status());
  return voxels;
}

// The grid an <ImageData> or <PImageData> element declares: its extent and index-to-world map.
struct ImageGeometry {
  Extent whole{};
  Index3 dims{};
  std::vector<double> origin;     // 3
  std::vector<double> spacing;    // 3
  std::vector<double> direction;  // 9, row-major; the identity when the file has none
  bool has_direction = false;

  // Column a is Direction's column a times Spacing[a]; the extent's first sample lies at
  // Origin + Direction (Spacing * first index).
  Affine affine() const {
    std::array<Vec3, 3> axes;
    Vec3 first = {origin[0], origin[1], origin[2]};
    for (int a = 0; a < 3; ++a) {
      for (int row = 0; row < 3; ++row) {
        axes[a][row] = direction[3 * row + a] * spacing[a];
        first[row] += axes[a][row] * static_cast<double>(whole[2 * a]);
      }
    }
    return AffineFromAxes(axes, first);
  }
};

absl::StatusOr<ImageGeometry> ReadGeometry(const VtkXmlFile& xml, absl::string_view path,
                                           pugi::xml_node image) {
  ImageGeometry g;
  absl::StatusOr<Extent> whole = ReadExtent(xml, path, image, "WholeExtent");
  if (!whole.ok()) return whole.status();
  g.whole = *whole;
  for (int a = 0; a < 3; ++a) {
    g.dims[a] = g.whole[2 * a + 1] - g.whole[2 * a] + 1;
    if (g.dims[a] < 2 || g.dims[a] > kMaxVolumeAxis) {
      return FileLineError(
          path, xml.LineOf(image),
          absl::StrCat("WholeExtent gives ", g.dims[a], " samples along ", std::string(1, "xyz"[a]),
                       ": a volume needs 2 to 2^20 per axis (trilinear needs a cell)"));
    }
  }
  absl::StatusOr<std::vector<double>> origin = Numbers(xml, path, image, "Origin", 3);
  if (!origin.ok()) return origin.status();
  g.origin = *std::move(origin);
  absl::StatusOr<std::vector<double>> spacing = Numbers(xml, path, image, "Spacing", 3);
  if (!spacing.ok()) return spacing.status();
  g.spacing = *std::move(spacing);
  g.direction = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  g.has_direction = image.attribute("Direction");
  if (g.has_direction) {
    absl::StatusOr<std::vector<double>> d = Numbers(xml, path, image, "Direction", 9);
    if (!d.ok()) return d.status();
    g.direction = *std::move(d);
  }
  return g;
}

// One <Piece> of an image, decoded: its extent (absolute indices) and its samples.
struct DecodedPiece {
  Extent extent{};
  PieceSamples samples;
};

// Every <Piece> of the <ImageData> of `xml`, each checked to lie inside `whole` (the extent of
// the image being assembled, which for a .pvti piece file is its parent's) and decoded against
// the bytes it really holds. Appends to `out`; `held` counts their samples.
absl::Status DecodePieces(const VtkXmlFile& xml, absl::string_view path, const Extent& whole,
                          std::vector<DecodedPiece>& out, uint64_t& held) {
  VtuArrayReader arrays(path, xml.encoding, xml.appended,
                        [&xml](pugi::xml_node node) { return xml.LineOf(node); });
  for (pugi::xml_node piece : xml.dataset.children("Piece")) {
    absl::StatusOr<Extent> extent = ReadExtent(xml, path, piece, "Extent");
    if (!extent.ok()) return extent.status();
    DecodedPiece d;
    d.extent = *extent;
    uint64_t count = 1;
    for (int a = 0; a < 3; ++a) {
      const int64_t lo = d.extent[2 * a], hi = d.extent[2 * a + 1];
      if (hi < lo || lo < whole[2 * a] || hi > whole[2 * a + 1]) {
        return FileLineError(path, xml.LineOf(piece),
                             "Piece Extent is empty or outside WholeExtent");
      }
      count *= static_cast<uint64_t>(hi - lo + 1);
    }
    absl::StatusOr<pugi::xml_node> array = SampleArray(xml, path, piece);
    if (!array.ok()) return array.status();
    absl::StatusOr<PieceSamples> samples = ReadSamples(xml, arrays, *array, count);
    if (!samples.ok()) return samples.status();
    if (!out.empty() && samples->type != out[0].samples.type) {
      return arrays.Error(*array, "has another type than the first piece's samples");
    }
    d.samples = *std::move(samples);
    held += count;
    out.push_back(std::move(d));
  }
  return absl::OkStatus();
}

// The whole image from its pieces. The image is allocated only when the pieces hold at least as
// many samples as the grid: a WholeExtent of 2^60 samples over one small piece is an error, not
// a 2^60-byte allocation.
absl::StatusOr<VolumeFile> Assemble(absl::string_view path, const ImageGeometry& g,
                                    std::vector<DecodedPiece> pieces, uint64_t held) {
  if (pieces.empty()) return FileError(path, "no <Piece>");
  const Index3& dims = g.dims;
  const uint64_t total = static_cast<uint64_t>(dims[0]) * dims[1] * dims[2];
  const StoredType type = pieces[0].samples.type;
  if (pieces.size() == 1 && held == total) {  // one piece holds the whole image: no assembly
    absl::StatusOr<DecodedVoxels> voxels = Widen(path, type, pieces[0].samples.data);
    if (!voxels.ok()) return voxels.status();
    pieces[0].samples.data = {};
    return PlaceOnGrid(path, g.affine(), dims, voxels->type, std::move(voxels->data));
  }
  if (held < total) {
    return FileError(path, absl::StrCat("the pieces hold ", held, " samples, fewer than the ",
                                        total, " of WholeExtent"));
  }
  const size_t width = StoredSize(type);
  std::string data(total * width, '\0');
  std::vector<bool> covered(total, false);
  uint64_t covered_count = 0;
  for (DecodedPiece& d : pieces) {
    Index3 n, offset;
    for (int a = 0; a < 3; ++a) {
      n[a] = d.extent[2 * a + 1] - d.extent[2 * a] + 1;
      offset[a] = d.extent[2 * a] - g.whole[2 * a];
    }
    for (int64_t z = 0; z < n[2]; ++z) {
      for (int64_t y = 0; y < n[1]; ++y) {
        const uint64_t row = static_cast<uint64_t>(y + n[1] * z) * n[0];
        const uint64_t at =
            static_cast<uint64_t>(offset[0]) +
            dims[0] * static_cast<uint64_t>(offset[1] + y + dims[1] * (offset[2] + z));
        std::memcpy(data.data() + at * width, d.samples.data.data() + row * width, n[0] * width);
        for (int64_t x = 0; x < n[0]; ++x) {
          if (!covered[at + x]) {
            covered[at + x] = true;
            ++covered_count;
          }
        }
      }
    }
    d.samples.data = {};
  }
  if (covered_count != total) {
    return FileError(path, absl::StrCat("the pieces cover ", covered_count, " of the ", total,
                                        " samples of WholeExtent"));
  }
  absl::StatusOr<DecodedVoxels> voxels = Widen(path, type, data);
  if (!voxels.ok()) return voxels.status();
  data = {};
  return PlaceOnGrid(path, g.affine(), dims, voxels->type, std::move(voxels->data));
}

// A .pvti index: its grid and the piece files it names, resolved against its directory.
struct PvtiIndex {
  ImageGeometry geometry;
  std::vector<std::string> sources;
};

absl::StatusOr<PvtiIndex> ParseIndex(absl::string_view text, absl::string_view path) {
  VtkXmlFile xml;
  if (absl::Status s = OpenVtkXml(text, path, "PImageData", xml); !s.ok()) return s;
  absl::StatusOr<ImageGeometry> g = ReadGeometry(xml, path, xml.dataset);
  if (!g.ok()) return g.status();
  absl::StatusOr<std::vector<std::string>> sources = PieceSources(xml, path);
  if (!sources.ok()) return sources.status();
  return PvtiIndex{*std::move(g), *std::move(sources)};
}

}  // namespace

absl::StatusOr<std::vector<std::string>> ParsePvtiIndex(absl::string_view text,
                                                        absl::string_view path) {
  absl::StatusOr<PvtiIndex> index = ParseIndex(text, path);
  if (!index.ok()) return index.status();
  return std::move(index->sources);
}

absl::StatusOr<VolumeFile> ParseVti(absl::string_view text, absl::string_view path) {
  VtkXmlFile xml;
  if (absl::Status s = OpenVtkXml(text, path, "ImageData", xml); !s.ok()) return s;
  absl::StatusOr<ImageGeometry> g = ReadGeometry(xml, path, xml.dataset);
  if (!g.ok()) return g.status();
  std::vector<DecodedPiece> pieces;
  uint64_t held = 0;
  if (absl::Status s = DecodePieces(xml, path, g->whole, pieces, held); !s.ok()) return s;
  return Assemble(path, *g, std::move(pieces), held);
}

absl::StatusOr<VolumeFile> ReadPvti(const std::string& path) {
  absl::StatusOr<FileView> file = FileView::Open(path);
  if (!file.ok()) return file.status();
  absl::StatusOr<PvtiIndex> index = ParseIndex(file->bytes(), path);
  if (!index.ok()) return index.status();
  ImageGeometry& g = index->geometry;
  // VTK 9.1's vtkXMLPImageDataWriter writes Direction into every piece but not into the index
  // (and its reader then drops it: an oblique image comes back axis-aligned). The pieces are
  // right, so an index without Direction takes theirs, which must agree.
  std::optional<std::vector<double>> piece_direction;
  std::vector<DecodedPiece> pieces;
  uint64_t held = 0;
  for (const std::string& piece_path : index->sources) {
    absl::StatusOr<FileView> piece_file = FileView::Open(piece_path);
    if (!piece_file.ok()) {
      return absl::Status(
          piece_file.status().code(),
          absl::StrCat(path, ": piece ", pieces.size(), ": ", piece_file.status().message()));
    }
    // The piece's own geometry is its extent within the parent's grid; the parent's Origin,
    // Spacing and Direction place it.
    VtkXmlFile piece_xml;
    if (absl::Status s = OpenVtkXml(piece_file->bytes(), piece_path, "ImageData", piece_xml);
        !s.ok()) {
      return s;
    }
    if (!g.has_direction && piece_xml.dataset.attribute("Direction")) {
      absl::StatusOr<std::vector<double>> d =
          Numbers(piece_xml, piece_path, piece_xml.dataset, "Direction", 9);
      if (!d.ok()) return d.status();
      if (piece_direction && *piece_direction != *d) {
        return FileLineError(piece_path, piece_xml.LineOf(piece_xml.dataset),
                             "Direction differs from the earlier pieces' (the index has none)");
      }
      piece_direction = *std::move(d);
    }
    if (absl::Status s = DecodePieces(piece_xml, piece_path, g.whole, pieces, held); !s.ok()) {
      return s;
    }
  }
  if (piece_direction) g.direction = *std::move(piece_direction);
  return Assemble(path, g, std::move(pieces), held);
}

absl::StatusOr<VolumeFile> ReadVti(const std::string& path) {
  absl::StatusOr<FileView> file = FileView::Open(path);
  if (!file.ok()) return file.status();
  return ParseVti(file->bytes(), path);
}

}  // namespace tetrefine::io
