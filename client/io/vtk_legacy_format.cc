#include "client/io/vtk_legacy_format.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <functional>
#include <limits>
#include <optional>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "absl/strings/ascii.h"
#include "absl/strings/match.h"
#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_join.h"
#include "absl/strings/strip.h"
#include "client/io/byte_order.h"
#include "client/io/file_bytes.h"
#include "client/io/grid_placement.h"
#include "client/io/io_error.h"
#include "client/io/label_names.h"
#include "client/io/mesh_frame.h"
#include "client/io/number_text.h"
#include "client/io/text_scanner.h"
#include "client/io/voxel_decode.h"
#include "client/io/vtk_cells.h"
#include "client/io/vtk_scalar.h"
#include "client/io/world_frame.h"
#include "core/huge_pages.h"

namespace tetrefine::io {
namespace {

constexpr int64_t kMaxCount = int64_t{1} << 40;

int HexDigit(char c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  return -1;
}

// VTK writes array names and ASCII strings with %XX escapes for spaces, '%' and other bytes
// that would break tokens.
std::string Unescape(absl::string_view text) {
  std::string out;
  for (size_t i = 0; i < text.size(); ++i) {
    if (text[i] == '%' && i + 2 < text.size() && HexDigit(text[i + 1]) >= 0 &&
        HexDigit(text[i + 2]) >= 0) {
      out.push_back(static_cast<char>(HexDigit(text[i + 1]) * 16 + HexDigit(text[i + 2])));
      i += 2;
    } else {
      out.push_back(text[i]);
    }
  }
  return out;
}

std::string Escape(absl::string_view text) {
  static constexpr char kHex[] = "0123456789ABCDEF";
  std::string out;
  for (char c : text) {
    const auto u = static_cast<unsigned char>(c);
    if (u <= ' ' || u > '~' || c == '%' || c == '"') {
      out += '%';
      out += kHex[u >> 4];
      out += kHex[u & 15];
    } else {
      out += c;
    }
  }
  return out.empty() ? std::string("label") : out;
}

class LegacyParser {
 public:
  // What the caller reads the file as: an UNSTRUCTURED_GRID mesh or a STRUCTURED_POINTS image.
  enum class Want { kMesh, kImage };
  LegacyParser(absl::string_view text, absl::string_view path, Want want)
      : in_(text, path), path_(path), want_(want) {}

  absl::StatusOr<MeshFile> ParseMesh();
  absl::StatusOr<VolumeFile> ParseImage();

 private:
  // The header lines and every section, into the members below.
  absl::Status Parse();
  // DIMENSIONS, SPACING (ASPECT_RATIO), ORIGIN and DIRECTION of a STRUCTURED_POINTS dataset.
  absl::Status ReadImageGeometry(const std::string& keyword);

  // Reads `count` values stored as `type` (a legacy type token) into `out`, ASCII or binary.
  // In a binary file the values start on the line after the header, so the rest of the header
  // line is consumed first.
  absl::Status ReadDoubles(int64_t count, absl::string_view type, absl::string_view what,
                           std::vector<double>& out);
  absl::Status ReadInts(int64_t count, absl::string_view type, absl::string_view what,
                        std::vector<int64_t>& out);
  // The image's `count` samples, of type sample_type_: a binary file's bytes as stored (widened
  // exactly later, by DecodeVoxels), an ASCII file's values as numbers.
  absl::Status ReadImageSamples(int64_t count, absl::string_view what);
  // Reads `count` strings (ASCII: one per line, %-escaped; binary: length-prefixed).
  absl::Status ReadStrings(int64_t count, std::vector<std::string>* out);
  // Skips `count` values of `type`, which may also be "bit" or "string".
  absl::Status SkipValues(int64_t count, absl::string_view type, absl::string_view what);
  absl::StatusOr<absl::string_view> BinaryBlock(int64_t count, size_t width,
                                                absl::string_view what);
  absl::Status SkipMetadata();

  absl::Status ReadCells();
  absl::Status ReadField(int64_t tuples_expected, bool point_section, bool dataset_level);
  absl::Status ReadAttribute(const std::string& keyword, int64_t n, bool point_section);
  // Where a named array goes: values, iteration, quality (doubles) or labels (ints).
  std::vector<double>* DoubleDestination(bool point_section, absl::string_view name);
  bool IsLabel(bool point_section, absl::string_view name) const;
  absl::Status ReadArray(absl::string_view name, int64_t components, int64_t n,
                         absl::string_view type, bool point_section);

  TextScanner in_;
  absl::string_view path_;
  int major_version_ = 0;
  bool binary_ = false;
  bool have_points_ = false;
  bool have_cells_ = false;
  bool have_types_ = false;
  std::vector<double> points_;
  VtkCells cells_;
  std::vector<double> values_;
  VtkCellData cell_data_;
  MeshFrame frame_ = MeshFrame::kUntagged;
  std::vector<std::string> dropped_;  // MeshFile::dropped_arrays

  Want want_;
  // STRUCTURED_POINTS: the grid, and the first one-component point array as its samples.
  bool have_dimensions_ = false;
  Index3 dimensions_{0, 0, 0};
  std::array<double, 3> spacing_{1.0, 1.0, 1.0};
  std::array<double, 3> origin_{0.0, 0.0, 0.0};
  std::array<double, 9> direction_{1, 0, 0, 0, 1, 0, 0, 0, 1};
  std::optional<VtkScalar> sample_type_;
  std::vector<double> samples_;  // ASCII files, and COLOR_SCALARS
  std::string sample_bytes_;     // binary files: the samples as stored (big-endian)
  bool binary_samples_ = false;  // the samples are sample_bytes_
  // ASCII uint32, int64 or uint64 samples beyond 2^53 (which the numbers may have rounded): the
  // largest magnitude among those written as integers, and among the others.
  uint64_t ascii_wide_integer_ = 0;
  double ascii_wide_other_ = 0.0;
};

absl::StatusOr<absl::string_view> LegacyParser::BinaryBlock(int64_t count, size_t width,
                                                            absl::string_view what) {
  if (count < 0 || count > kMaxCount) return in_.Error(absl::StrCat("bad count of ", what));
  in_.RestOfLine();
  return in_.Bytes(static_cast<size_t>(count) * width, what);
}

absl::Status LegacyParser::ReadDoubles(int64_t count, absl::string_view type,
                                       absl::string_view what, std::vector<double>& out) {
  const std::optional<VtkScalar> scalar = VtkScalarFromLegacy(type);
  if (!scalar)
    return in_.Error(absl::StrCat("unsupported data type ", QuoteToken(type), " for ", what));
  if (binary_) {
    absl::StatusOr<absl::string_view> bytes = BinaryBlock(count, VtkScalarSize(*scalar), what);
    if (!bytes.ok()) return bytes.status();
    ReserveHuge(out, count);
    out.resize(count);
    ScalarsToDoubles(*bytes, *scalar, ByteOrder::kBig, count, out.data());
    return absl::OkStatus();
  }
  if (absl::Status s = in_.CheckCount(count, 2, what); !s.ok()) return s;
  ReserveHuge(out, count);
  out.resize(count);
  for (double& x : out) {
    absl::StatusOr<double> value = in_.Double(what);
    if (!value.ok()) return value.status();
    x = *value;
  }
  return absl::OkStatus();
}

absl::Status LegacyParser::ReadImageSamples(int64_t count, absl::string_view what) {
  if (binary_) {
    absl::StatusOr<absl::string_view> bytes =
        BinaryBlock(count, VtkScalarSize(*sample_type_), what);
    if (!bytes.ok()) return bytes.status();
    sample_bytes_ = std::string(*bytes);
    binary_samples_ = true;
    return absl::OkStatus();
  }
  if (absl::Status s = in_.CheckCount(count, 2, what); !s.ok()) return s;
  ReserveHuge(samples_, count);
  samples_.resize(count);
  const bool wide = *sample_type_ == VtkScalar::kUInt32 || *sample_type_ == VtkScalar::kInt64 ||
                    *sample_type_ == VtkScalar::kUInt64;
  for (double& x : samples_) {
    absl::StatusOr<absl::string_view> token = in_.Token(what);
    if (!token.ok()) return token.status();
    if (!ParseDouble(*token, x)) {
      return in_.Error(absl::StrCat("expected ", what, " (a number), got ", QuoteToken(*token)));
    }
    // A finite value from 2^53 up (NaN and infinities go on to float64, whose check names the
    // voxel): its magnitude, exact when written as a 64-bit integer (2^53 + 1 reads as 2^53).
    if (wide && std::isfinite(x) && !(std::abs(x) < 0x1p53)) {
      int64_t signed_value;
      uint64_t unsigned_value;
      if (absl::SimpleAtoi(*token, &unsigned_value)) {
        ascii_wide_integer_ = std::max(ascii_wide_integer_, unsigned_value);
      } else if (absl::SimpleAtoi(*token, &signed_value)) {
        ascii_wide_integer_ =
            std::max(ascii_wide_integer_, signed_value < 0
                                              ? uint64_t{0} - static_cast<uint64_t>(signed_value)
                                              : static_cast<uint64_t>(signed_value));
      } else {
        ascii_wide_other_ = std::max(ascii_wide_other_, std::abs(x));
      }
    }
  }
  return absl::OkStatus();
}

absl::Status LegacyParser::ReadInts(int64_t count, absl::string_view type, absl::string_view what,
                                    std::vector<int64_t>& out) {
  const std::optional<VtkScalar> scalar = VtkScalarFromLegacy(type);
  if (!scalar)
    return in_.Error(absl::StrCat("unsupported data type ", QuoteToken(type), " for ", what));
  if (binary_) {
    absl::StatusOr<absl::string_view> bytes = BinaryBlock(count, VtkScalarSize(*scalar), what);
    if (!bytes.ok()) return bytes.status();
    ReserveHuge(out, count);
    out.resize(count);
    const size_t bad = ScalarsToInt64s(*bytes, *scalar, ByteOrder::kBig, count, out.data());
    if (bad != static_cast<size_t>(count)) {
      return in_.Error(absl::StrCat(what, ": value ", bad, " is ",
                                    ScalarAt(*bytes, *scalar, ByteOrder::kBig, bad),
                                    ", not an integer"));
    }
    return absl::OkStatus();
  }
  if (absl::Status s = in_.CheckCount(count, 2, what); !s.ok()) return s;
  ReserveHuge(out, count);
  out.resize(count);
  for (int64_t& x : out) {
    absl::StatusOr<double> value = in_.Double(what);
    if (!value.ok()) return value.status();
    if (!(std::abs(*value) < 0x1p62) || *value != std::floor(*value)) {
      return in_.Error(absl::StrCat(what, ": ", *value, " is not an integer"));
    }
    x = static_cast<int64_t>(*value);
  }
  return absl::OkStatus();
}

absl::Status LegacyParser::ReadStrings(int64_t count, std::vector<std::string>* out) {
  if (count < 0 || count > kMaxCount) return in_.Error("bad string count");
  if (!binary_) {
    in_.RestOfLine();
    if (absl::Status s = in_.CheckCount(count, 1, "strings"); !s.ok()) return s;
    for (int64_t i = 0; i < count; ++i) {
      if (in_.AtEndOfInput()) return in_.Error("truncated in a string array");
      const std::string value = Unescape(in_.RestOfLine());
      if (out != nullptr) out->push_back(value);
    }
    return absl::OkStatus();
  }
  in_.RestOfLine();
  for (int64_t i = 0; i < count; ++i) {
    absl::StatusOr<absl::string_view> head = in_.Bytes(1, "a string length");
    if (!head.ok()) return head.status();
    const auto first = static_cast<unsigned char>((*head)[0]);
    // The top two bits say how many bytes hold the length: 11 one, 10 two, 01 four, 00 eight.
    const int width = (first >> 6) == 3 ? 1 : (first >> 6) == 2 ? 2 : (first >> 6) == 1 ? 4 : 8;
    uint64_t length = first & 0x3f;
    if (width > 1) {
      absl::StatusOr<absl::string_view> rest = in_.Bytes(width - 1, "a string length");
      if (!rest.ok()) return rest.status();
      for (char c : *rest) length = (length << 8) | static_cast<unsigned char>(c);
    }
    absl::StatusOr<absl::string_view> value = in_.Bytes(length, "a string");
    if (!value.ok()) return value.status();
    if (out != nullptr) out->emplace_back(*value);
  }
  return absl::OkStatus();
}

absl::Status LegacyParser::SkipValues(int64_t count, absl::string_view type,
                                      absl::string_view what) {
  if (absl::EqualsIgnoreCase(type, "string")) return ReadStrings(count, nullptr);
  if (absl::EqualsIgnoreCase(type, "bit")) {
    if (binary_) {
      absl::StatusOr<absl::string_view> bytes = BinaryBlock((count + 7) / 8, 1, what);
      return bytes.status();
    }
  } else if (binary_) {
    const std::optional<VtkScalar> scalar = VtkScalarFromLegacy(type);
    if (!scalar)
      return in_.Error(absl::StrCat("unsupported data type ", QuoteToken(type), " for ", what));
    return BinaryBlock(count, VtkScalarSize(*scalar), what).status();
  }
  if (absl::Status s = in_.CheckCount(count, 2, what); !s.ok()) return s;
  for (int64_t i = 0; i < count; ++i) {
    if (absl::Status s = in_.Double(what).status(); !s.ok()) return s;
  }
  return absl::OkStatus();
}

// METADATA (VTK 5.1+, also in 4.2 files VTK 9 writes): text lines up to an empty line.
absl::Status LegacyParser::SkipMetadata() {
  in_.RestOfLine();  // the rest of the METADATA line itself
  while (!in_.AtEndOfInput() && !absl::StripAsciiWhitespace(in_.RestOfLine()).empty()) {
  }
  return absl::OkStatus();
}

absl::Status LegacyParser::ReadCells() {
  absl::StatusOr<int64_t> first = in_.IntIn("the CELLS count", 0, kMaxCount);
  if (!first.ok()) return first.status();
  absl::StatusOr<int64_t> second = in_.IntIn("the CELLS size", 0, kMaxCount);
  if (!second.ok()) return second.status();
  if (major_version_ >= 5) {
    // "CELLS <offsets> <connectivity>" then "OFFSETS <type>" and "CONNECTIVITY <type>".
    if (!in_.ConsumeIf("OFFSETS")) return in_.Error("expected OFFSETS after CELLS (version 5)");
    absl::StatusOr<absl::string_view> type = in_.Token("the OFFSETS type");
    if (!type.ok()) return type.status();
    if (absl::Status s = ReadInts(*first, *type, "cell offsets", cells_.offsets); !s.ok()) {
      return s;
    }
    if (!in_.ConsumeIf("CONNECTIVITY")) return in_.Error("expected CONNECTIVITY after OFFSETS");
    type = in_.Token("the CONNECTIVITY type");
    if (!type.ok()) return type.status();
    return ReadInts(*second, *type, "cell connectivity", cells_.connectivity);
  }
  // "CELLS <n> <size>" then n runs "k i_1 ... i_k" (int32 in binary files).
  std::vector<int64_t> flat;
  if (absl::Status s = ReadInts(*second, "int", "cell entries", flat); !s.ok()) return s;
  if (*first > *second) return in_.Error("CELLS count exceeds its size");
  cells_.offsets.assign(1, 0);
  cells_.offsets.reserve(*first + 1);
  cells_.connectivity.reserve(*second - *first);
  size_t at = 0;
  for (int64_t c = 0; c < *first; ++c) {
    if (at >= flat.size()) return in_.Error(absl::StrCat("CELLS ends inside cell ", c));
    const int64_t k = flat[at++];
    if (k < 0 || static_cast<uint64_t>(k) > flat.size() - at) {
      return in_.Error(absl::StrCat("cell ", c, " claims ", k, " points, beyond CELLS size"));
    }
    cells_.connectivity.insert(cells_.connectivity.end(), flat.begin() + at, flat.begin() + at + k);
    at += k;
    cells_.offsets.push_back(static_cast<int64_t>(cells_.connectivity.size()));
  }
  if (at != flat.size()) {
    return in_.Error(
        absl::StrCat("CELLS size ", *second, " does not match the ", at, " numbers its cells use"));
  }
  return absl::OkStatus();
}

std::vector<double>* LegacyParser::DoubleDestination(bool point_section, absl::string_view name) {
  if (want_ == Want::kImage) return point_section && !sample_type_ ? &samples_ : nullptr;
  if (point_section) return name == "value" ? &values_ : nullptr;
  if (name == "iteration") return &cell_data_.iteration;
  if (name == "quality") return &cell_data_.quality;
  return nullptr;
}

bool LegacyParser::IsLabel(bool point_section, absl::string_view name) const {
  if (point_section || want_ == Want::kImage) return false;
  const int rank = LabelNameRank(name);
  return rank >= 0 && (cell_data_.label_rank < 0 || rank < cell_data_.label_rank);
}

absl::Status LegacyParser::ReadArray(absl::string_view raw_name, int64_t components, int64_t n,
                                     absl::string_view type, bool point_section) {
  const std::string name = Unescape(raw_name);
  if (components == 1) {
    if (std::vector<double>* out = DoubleDestination(point_section, name)) {
      if (want_ == Want::kImage) {  // the image's samples, whatever their name
        sample_type_ = VtkScalarFromLegacy(type);
        if (!sample_type_) {
          return in_.Error(absl::StrCat("unsupported data type ", QuoteToken(type), " for ", name));
        }
        return ReadImageSamples(n, name);
      }
      return ReadDoubles(n, type, name, *out);
    }
    if (want_ != Want::kImage && IsGhostArrayName(name)) {
      if (point_section) return SkipValues(n, type, name);  // see ParseVtu
      std::vector<int64_t> flags;
      if (absl::Status s = ReadInts(n, type, name, flags); !s.ok()) return s;
      return GhostCellFlags(name, flags, path_, &cell_data_);
    }
    if (IsLabel(point_section, name)) {
      // A label array the file prefers (LabelNameRank) replaces one read before.
      if (cell_data_.label_rank >= 0)
        dropped_.push_back(DroppedArray(false, cell_data_.label_name));
      if (absl::Status s = ReadInts(n, type, name, cell_data_.label); !s.ok()) return s;
      cell_data_.label_name = name;
      cell_data_.label_rank = LabelNameRank(name);
      return absl::OkStatus();
    }
  }
  dropped_.push_back(DroppedArray(point_section, name));
  return SkipValues(n * components, type, name);
}

absl::Status LegacyParser::ReadField(int64_t tuples_expected, bool point_section,
                                     bool dataset_level) {
  if (absl::Status s = in_.Token("the FIELD name").status(); !s.ok()) return s;
  absl::StatusOr<int64_t> arrays = in_.IntIn("the FIELD array count", 0, 1 << 20);
  if (!arrays.ok()) return arrays.status();
  for (int64_t a = 0; a < *arrays; ++a) {
    absl::StatusOr<absl::string_view> name = in_.Token("a FIELD array name");
    if (!name.ok()) return name.status();
    const std::string array_name(*name);
    absl::StatusOr<int64_t> components = in_.IntIn("a FIELD component count", 1, 1 << 20);
    if (!components.ok()) return components.status();
    absl::StatusOr<int64_t> tuples = in_.IntIn("a FIELD tuple count", 0, kMaxCount);
    if (!tuples.ok()) return tuples.status();
    absl::StatusOr<absl::string_view> type = in_.Token("a FIELD array type");
    if (!type.ok()) return type.status();
    const std::string type_name(*type);
    if (dataset_level) {
      if (array_name == "SPACE" && absl::EqualsIgnoreCase(type_name, "string")) {
        std::vector<std::string> strings;
        if (absl::Status s = ReadStrings(*components * *tuples, &strings); !s.ok()) return s;
        if (!strings.empty() && frame_ == MeshFrame::kUntagged) {
          frame_ = absl::StrContains(strings[0], "LPS")   ? MeshFrame::kLps
                   : absl::StrContains(strings[0], "RAS") ? MeshFrame::kRas
                                                          : MeshFrame::kUntagged;
        }
      } else if (absl::Status s = SkipValues(*components * *tuples, type_name, array_name);
                 !s.ok()) {
        return s;
      }
    } else {
      const bool wanted =
          *components == 1 && (DoubleDestination(point_section, Unescape(array_name)) != nullptr ||
                               IsLabel(point_section, Unescape(array_name)));
      if (wanted && *tuples != tuples_expected) {
        return in_.Error(absl::StrCat("array \"", array_name, "\" has ", *tuples,
                                      " tuples, expected ", tuples_expected));
      }
      if (absl::Status s = ReadArray(array_name, *components, *tuples, type_name, point_section);
          !s.ok()) {
        return s;
      }
    }
    if (in_.ConsumeIf("METADATA")) {
      if (absl::Status s = SkipMetadata(); !s.ok()) return s;
    }
  }
  return absl::OkStatus();
}

// One attribute (SCALARS, FIELD, VECTORS, ...) of a POINT_DATA/CELL_DATA section of `n` tuples.
absl::Status LegacyParser::ReadAttribute(const std::string& keyword, int64_t n,
                                         bool point_section) {
  if (keyword == "scalars") {
    absl::StatusOr<absl::string_view> name = in_.Token("the SCALARS name");
    if (!name.ok()) return name.status();
    const std::string array_name(*name);
    absl::StatusOr<absl::string_view> type = in_.Token("the SCALARS type");
    if (!type.ok()) return type.status();
    const std::string type_name(*type);
    // The component count is optional; the next token is then LOOKUP_TABLE or a number.
    int64_t components = 1;
    const absl::string_view rest = absl::StripAsciiWhitespace(in_.RestOfLine());
    if (!rest.empty() && !ParseInt64(rest, components)) {
      return in_.Error(absl::StrCat("bad SCALARS component count \"", rest.substr(0, 20), "\""));
    }
    if (components < 1 || components > 4) return in_.Error("SCALARS needs 1 to 4 components");
    if (in_.ConsumeIf("LOOKUP_TABLE")) {
      if (absl::Status s = in_.Token("the lookup table name").status(); !s.ok()) return s;
    }
    return ReadArray(array_name, components, n, type_name, point_section);
  }
  if (keyword == "field") return ReadField(n, point_section, false);
  // Attributes kept only to be skipped: numbers per tuple.
  int64_t width = 0;
  if (keyword == "vectors" || keyword == "normals") width = 3;
  if (keyword == "tensors") width = 9;
  if (keyword == "tensors6") width = 6;
  if (width > 0 || keyword == "texture_coordinates" || keyword == "color_scalars") {
    // A named attribute this reader does not keep.
    absl::StatusOr<absl::string_view> name = in_.Token("the attribute name");
    if (!name.ok()) return name.status();
    dropped_.push_back(DroppedArray(point_section, Unescape(*name)));
  }
  if (width > 0) {
    absl::StatusOr<absl::string_view> type = in_.Token("the attribute type");
    if (!type.ok()) return type.status();
    return SkipValues(n * width, std::string(*type), keyword);
  }
  if (keyword == "texture_coordinates") {
    absl::StatusOr<int64_t> dim = in_.IntIn("the attribute width", 1, 16);
    if (!dim.ok()) return dim.status();
    absl::StatusOr<absl::string_view> type = in_.Token("the attribute type");
    if (!type.ok()) return type.status();
    return SkipValues(n * *dim, std::string(*type), keyword);
  }
  if (keyword == "color_scalars") {
    // Floats in ASCII files, unsigned chars in binary ones.
    absl::StatusOr<int64_t> dim = in_.IntIn("the attribute width", 1, 16);
    if (!dim.ok()) return dim.status();
    if (*dim == 1 && point_section && want_ == Want::kImage && !sample_type_) {
      // vtkStructuredPointsWriter stores unsigned char scalars this way: the image's samples.
      // ASCII holds them as v / 255 with 6 digits; VTK's reader takes 255 f + 0.5 back to the
      // byte, and so does this one.
      dropped_.pop_back();
      sample_type_ = VtkScalar::kUInt8;
      if (binary_) return ReadDoubles(n, "unsigned_char", "color scalars", samples_);
      if (absl::Status s = ReadDoubles(n, "float", "color scalars", samples_); !s.ok()) return s;
      for (double& v : samples_) v = std::floor(255.0 * std::clamp(v, 0.0, 1.0) + 0.5);
      return absl::OkStatus();
    }
    return SkipValues(n * *dim, binary_ ? "unsigned_char" : "float", keyword);
  }
  if (keyword == "lookup_table") {
    if (absl::Status s = in_.Token("the lookup table name").status(); !s.ok()) return s;
    absl::StatusOr<int64_t> size = in_.IntIn("the lookup table size", 0, kMaxCount);
    if (!size.ok()) return size.status();
    return SkipValues(4 * *size, binary_ ? "unsigned_char" : "float", "lookup table");
  }
  if (keyword == "metadata") return SkipMetadata();
  return in_.Error(absl::StrCat("unknown keyword ", QuoteToken(keyword)));
}

absl::Status LegacyParser::ReadImageGeometry(const std::string& keyword) {
  if (keyword == "dimensions") {
    for (int a = 0; a < 3; ++a) {
      absl::StatusOr<int64_t> n = in_.IntIn("a DIMENSIONS size", 1, kMaxVolumeAxis);
      if (!n.ok()) return n.status();
      dimensions_[a] = *n;
    }
    have_dimensions_ = true;
    return absl::OkStatus();
  }
  const auto read = [this, &keyword](double* out, int n) -> absl::Status {
    for (int i = 0; i < n; ++i) {
      absl::StatusOr<double> value = in_.FiniteDouble(absl::AsciiStrToUpper(keyword));
      if (!value.ok()) return value.status();
      out[i] = *value;
    }
    return absl::OkStatus();
  };
  if (keyword == "spacing" || keyword == "aspect_ratio") return read(spacing_.data(), 3);
  if (keyword == "origin") return read(origin_.data(), 3);
  return read(direction_.data(), 9);  // "direction": row-major, as vtkImageData's
}

absl::Status LegacyParser::Parse() {
  // The three header lines are read whole, which moves the scanner to the next line: errors
  // name the line read (they named the one after it: an outside review, 2026-11-28).
  const int64_t first_line = in_.line();
  absl::string_view header = in_.RestOfLine();
  if (!absl::ConsumePrefix(&header, "# vtk DataFile Version ")) {
    return in_.ErrorAt(first_line,
                       "not a legacy VTK file: first line is not \"# vtk DataFile Version x.y\"");
  }
  if (header.empty() || !absl::ascii_isdigit(header[0])) {
    return in_.ErrorAt(first_line, "bad legacy VTK version");
  }
  major_version_ = header[0] - '0';
  frame_ = FrameFromHeader(in_.RestOfLine());  // the title
  const int64_t format_line = in_.line();
  const std::string format = absl::AsciiStrToUpper(absl::StripAsciiWhitespace(in_.RestOfLine()));
  if (format == "BINARY") {
    binary_ = true;
  } else if (format != "ASCII") {
    return in_.ErrorAt(format_line, "third line must be ASCII or BINARY");
  }

  int64_t section_size = -1;  // tuples in the current POINT_DATA / CELL_DATA section
  bool point_section = false;
  while (!in_.AtEnd()) {
    absl::StatusOr<absl::string_view> token = in_.Token("a keyword");
    if (!token.ok()) return token.status();
    const std::string keyword = absl::AsciiStrToLower(*token);
    if (keyword == "dataset") {
      absl::StatusOr<absl::string_view> kind = in_.Token("the dataset type");
      if (!kind.ok()) return kind.status();
      const bool image = absl::EqualsIgnoreCase(*kind, "STRUCTURED_POINTS");
      if (want_ == Want::kMesh && image) {
        return in_.Error(
            "DATASET STRUCTURED_POINTS is a volume (an image), not a tetrahedral mesh: read it "
            "as a volume (--volume)");
      }
      if (want_ == Want::kImage && !image) {
        return in_.Error(absl::StrCat(
            "DATASET ", QuoteToken(*kind), ": only STRUCTURED_POINTS holds a volume",
            absl::EqualsIgnoreCase(*kind, "UNSTRUCTURED_GRID") ? " (this is a mesh: --mesh)" : ""));
      }
      if (!image && !absl::EqualsIgnoreCase(*kind, "UNSTRUCTURED_GRID")) {
        return in_.Error(absl::StrCat("DATASET ", QuoteToken(*kind),
                                      ": only UNSTRUCTURED_GRID holds a tetrahedral mesh"));
      }
    } else if (want_ == Want::kImage && section_size < 0 &&
               (keyword == "dimensions" || keyword == "spacing" || keyword == "aspect_ratio" ||
                keyword == "origin" || keyword == "direction")) {
      if (absl::Status s = ReadImageGeometry(keyword); !s.ok()) return s;
    } else if (keyword == "points") {
      absl::StatusOr<int64_t> n = in_.IntIn("the POINTS count", 0, (int64_t{1} << 32) - 1);
      if (!n.ok()) return n.status();
      absl::StatusOr<absl::string_view> type = in_.Token("the POINTS type");
      if (!type.ok()) return type.status();
      if (absl::Status s = ReadDoubles(3 * *n, std::string(*type), "point coordinates", points_);
          !s.ok()) {
        return s;
      }
      have_points_ = true;
    } else if (keyword == "metadata") {
      if (absl::Status s = SkipMetadata(); !s.ok()) return s;
    } else if (keyword == "field" && section_size < 0) {
      if (absl::Status s = ReadField(-1, false, true); !s.ok()) return s;
    } else if (keyword == "cells") {
      if (absl::Status s = ReadCells(); !s.ok()) return s;
      have_cells_ = true;
    } else if (keyword == "cell_types") {
      absl::StatusOr<int64_t> n = in_.IntIn("the CELL_TYPES count", 0, kMaxCount);
      if (!n.ok()) return n.status();
      if (absl::Status s = ReadInts(*n, "int", "cell types", cells_.types); !s.ok()) return s;
      have_types_ = true;
    } else if (keyword == "point_data" || keyword == "cell_data") {
      absl::StatusOr<int64_t> n = in_.IntIn(absl::StrCat("the ", *token, " count"), 0, kMaxCount);
      if (!n.ok()) return n.status();
      section_size = *n;
      point_section = keyword == "point_data";
      size_t expected = point_section ? points_.size() / 3 : cells_.types.size();
      if (want_ == Want::kImage) {
        if (!have_dimensions_) return in_.Error(absl::StrCat(*token, " before DIMENSIONS"));
        expected = 1;
        for (int a = 0; a < 3; ++a) {
          expected *= static_cast<size_t>(point_section ? dimensions_[a]
                                                        : std::max<int64_t>(dimensions_[a] - 1, 1));
        }
      }
      if (static_cast<size_t>(*n) != expected) {
        return in_.Error(absl::StrCat(*token, " ", *n, " does not match the ", expected,
                                      point_section ? " points" : " cells"));
      }
    } else if (section_size >= 0) {
      if (absl::Status s = ReadAttribute(keyword, section_size, point_section); !s.ok()) {
        return s;
      }
    } else {
      return in_.Error(absl::StrCat("unexpected keyword ", QuoteToken(*token)));
    }
  }
  return absl::OkStatus();
}

absl::StatusOr<MeshFile> LegacyParser::ParseMesh() {
  if (absl::Status s = Parse(); !s.ok()) return s;
  if (!have_points_ || !have_cells_ || !have_types_) {
    return in_.Error("truncated: POINTS, CELLS and CELL_TYPES are all required");
  }
  if (major_version_ < 5 && cells_.offsets.size() != cells_.types.size() + 1) {
    return in_.Error(absl::StrCat("CELL_TYPES has ", cells_.types.size(), " entries for ",
                                  cells_.offsets.size() - 1, " cells"));
  }
  MeshFile file;
  file.frame = frame_;
  const size_t v = points_.size() / 3;
  ReserveHuge(file.mesh.points, v);
  file.mesh.points.resize(v);
  for (size_t i = 0; i < v; ++i) {
    file.mesh.points[i] = {points_[3 * i], points_[3 * i + 1], points_[3 * i + 2]};
  }
  file.mesh.values = std::move(values_);
  file.dropped_arrays = std::move(dropped_);
  if (absl::Status s = CellsToTets(cells_, cell_data_, v, path_, file); !s.ok()) return s;
  FrameToRas(file);
  DropNonFiniteDerivedArrays(&file);
  if (absl::Status s = ValidateMeshFile(file, path_); !s.ok()) return s;
  return file;
}

// Packs `values` as `T` when every value is one (binary files: always, they were read from T),
// into `out`; false otherwise (an ASCII "short" array holding 3.5 or 1e6).
template <typename T>
bool PackExactly(const std::vector<double>& values, std::vector<std::byte>& out) {
  out.resize(values.size() * sizeof(T));
  for (size_t i = 0; i < values.size(); ++i) {
    const double v = values[i];
    if constexpr (!std::is_floating_point_v<T>) {
      if (!(v >= static_cast<double>(std::numeric_limits<T>::min()) &&
            v <= static_cast<double>(std::numeric_limits<T>::max())) ||
          v != std::floor(v)) {
        return false;
      }
    }
    const T x = static_cast<T>(v);
    if (static_cast<double>(x) != v && !std::isnan(v)) return false;
    std::memcpy(out.data() + i * sizeof(T), &x, sizeof(T));
  }
  return true;
}

absl::StatusOr<VolumeFile> LegacyParser::ParseImage() {
  if (absl::Status s = Parse(); !s.ok()) return s;
  if (!have_dimensions_) return in_.Error("truncated: DATASET STRUCTURED_POINTS needs DIMENSIONS");
  for (int a = 0; a < 3; ++a) {
    if (dimensions_[a] < 2) {
      return in_.Error(absl::StrCat("DIMENSIONS gives ", dimensions_[a], " samples along ",
                                    std::string(1, "xyz"[a]),
                                    ": a volume needs at least 2 per axis (trilinear needs a "
                                    "cell)"));
    }
  }
  if (!sample_type_) {
    return in_.Error(
        dropped_.empty()
            ? std::string("no POINT_DATA SCALARS: the image has no samples")
            : absl::StrCat("no one-component POINT_DATA array to sample (the file has ",
                           absl::StrJoin(dropped_, ", "), ")"));
  }
  // Sample (i, j, k) at ORIGIN + DIRECTION (SPACING * (i, j, k)), as vtkImageData places it.
  std::array<Vec3, 3> axes;
  for (int a = 0; a < 3; ++a) {
    for (int row = 0; row < 3; ++row) axes[a][row] = direction_[3 * row + a] * spacing_[a];
  }
  Affine affine = AffineFromAxes(axes, {origin_[0], origin_[1], origin_[2]});
  if (frame_ == MeshFrame::kLps) affine = LpsToRas(affine);
  if (binary_samples_) {
    // The stored values, widened exactly where a volume lacks their type (DecodeVoxels).
    absl::StatusOr<DecodedVoxels> voxels =
        DecodeVoxels(sample_bytes_, StoredTypeOfVtk(*sample_type_), ByteOrder::kBig, 0, 0);
    sample_bytes_ = {};
    if (!voxels.ok()) return WithPath(path_, voxels.status());
    return PlaceOnGrid(path_, affine, dimensions_, voxels->type, std::move(voxels->data));
  }
  // ASCII values as DecodeVoxels widens stored ones: uint32, int64 and uint64 beyond 2^53 are
  // refused, as float64 would round them.
  if (ascii_wide_integer_ > (uint64_t{1} << 53) || ascii_wide_other_ > 0x1p53) {
    const StoredType stored = StoredTypeOfVtk(*sample_type_);
    return WithPath(
        path_, TooWideError(stored, static_cast<double>(ascii_wide_integer_) >= ascii_wide_other_
                                        ? absl::StrCat(ascii_wide_integer_)
                                        : absl::StrCat(ascii_wide_other_)));
  }
  // The file's own type where a volume can keep it and every value is one (int32 for uint32,
  // int64 and uint64); float64 otherwise.
  VoxelType type = VoxelType::kFloat64;
  std::vector<std::byte> data;
  bool packed = false;
  switch (*sample_type_) {
    case VtkScalar::kUInt8:
      packed = PackExactly<uint8_t>(samples_, data);
      type = VoxelType::kUint8;
      break;
    case VtkScalar::kInt8:
    case VtkScalar::kInt16:
      packed = PackExactly<int16_t>(samples_, data);
      type = VoxelType::kInt16;
      break;
    case VtkScalar::kUInt16:
      packed = PackExactly<uint16_t>(samples_, data);
      type = VoxelType::kUint16;
      break;
    case VtkScalar::kInt32:
    case VtkScalar::kUInt32:
    case VtkScalar::kInt64:
    case VtkScalar::kUInt64:
      packed = PackExactly<int32_t>(samples_, data);
      type = VoxelType::kInt32;
      break;
    case VtkScalar::kFloat32:
      packed = PackExactly<float>(samples_, data);
      type = VoxelType::kFloat32;
      break;
    default:
      break;
  }
  if (!packed) {
    type = VoxelType::kFloat64;
    PackExactly<double>(samples_, data);
  }
  samples_.clear();
  samples_.shrink_to_fit();
  return PlaceOnGrid(path_, affine, dimensions_, type, std::move(data));
}

// Appends `values` in the file's format: ASCII text (one value per line) or big-endian bytes.
template <typename T>
void AppendValues(std::string& out, const T* values, size_t n, bool binary) {
  if (binary) {
    const size_t start = out.size();
    out.resize(start + n * sizeof(T));
    char* at = out.data() + start;
    for (size_t i = 0; i < n; ++i) {
      std::memcpy(at + i * sizeof(T), &values[i], sizeof(T));
      if (kNativeOrder != ByteOrder::kBig)
        std::reverse(at + i * sizeof(T), at + (i + 1) * sizeof(T));
    }
    out += '\n';
    return;
  }
  for (size_t i = 0; i < n; ++i) {
    if constexpr (std::is_same_v<T, double>) {
      AppendDouble(out, values[i]);
    } else if constexpr (std::is_same_v<T, float>) {
      AppendFloat(out, values[i]);
    } else {
      absl::StrAppend(&out, values[i]);
    }
    out += '\n';
  }
}

}  // namespace

absl::StatusOr<MeshFile> ParseVtkLegacy(absl::string_view text, absl::string_view path) {
  return LegacyParser(text, path, LegacyParser::Want::kMesh).ParseMesh();
}

absl::StatusOr<VolumeFile> ParseVtkLegacyImage(absl::string_view text, absl::string_view path) {
  return LegacyParser(text, path, LegacyParser::Want::kImage).ParseImage();
}

absl::StatusOr<VolumeFile> ReadVtkLegacyImage(const std::string& path) {
  absl::StatusOr<FileView> file = FileView::Open(path);
  if (!file.ok()) return file.status();
  return ParseVtkLegacyImage(file->bytes(), path);
}

bool IsVtkLegacyImage(const std::string& path) {
  absl::StatusOr<FileView> file = FileView::Open(path);
  if (!file.ok()) return false;
  // The DATASET line follows the three header lines; 1 KiB holds it in any file VTK writes.
  TextScanner in(file->bytes().substr(0, 1024), path);
  for (int line = 0; line < 3 && !in.AtEndOfInput(); ++line) in.RestOfLine();
  if (!in.ConsumeIf("DATASET")) return false;
  absl::StatusOr<absl::string_view> kind = in.Token("the dataset type");
  return kind.ok() && absl::EqualsIgnoreCase(*kind, "STRUCTURED_POINTS");
}

std::string FormatVtkLegacy(const MeshFile& file, const VtkLegacyWriteOptions& options) {
  const Mesh& mesh = file.mesh;
  const size_t v = mesh.points.size();
  const size_t t = mesh.tets.size();
  const bool binary = options.binary;
  const bool wide = v > static_cast<size_t>(std::numeric_limits<int32_t>::max());
  std::string out =
      absl::StrCat("# vtk DataFile Version ", wide ? "5.1" : "4.2", "\ntetrefine mesh");
  if (binary) {
    // Binary sizes are known: the headers, points and values (32 bytes a vertex), cells and
    // types (24 a tet, 44 with 64-bit offsets and indices), three cell arrays (12). Grown
    // instead, the file was copied into a doubled buffer a few times over, each on fresh pages.
    ReserveHuge(out, 4096 + LabelArrayName(file).size() + v * 32 + t * (wide ? 44 + 12 : 24 + 12));
  }
  if (file.frame != MeshFrame::kUntagged) absl::StrAppend(&out, " SPACE=", FrameTag(file.frame));
  absl::StrAppend(&out, "\n", binary ? "BINARY" : "ASCII", "\nDATASET UNSTRUCTURED_GRID\n");
  absl::StrAppend(&out, "POINTS ", v, " double\n");
  {
    std::vector<double> xyz(3 * v);
    for (size_t i = 0; i < v; ++i) {
      for (int a = 0; a < 3; ++a) xyz[3 * i + a] = FrameSign(file.frame, a) * mesh.points[i][a];
    }
    if (binary) {
      AppendValues(out, xyz.data(), xyz.size(), true);
    } else {
      for (size_t i = 0; i < v; ++i) {
        AppendDouble(out, xyz[3 * i]);
        out += ' ';
        AppendDouble(out, xyz[3 * i + 1]);
        out += ' ';
        AppendDouble(out, xyz[3 * i + 2]);
        out += '\n';
      }
    }
  }
  if (wide) {
    absl::StrAppend(&out, "CELLS ", t + 1, " ", 4 * t, "\nOFFSETS vtktypeint64\n");
    std::vector<int64_t> offsets(t + 1);
    for (size_t i = 0; i <= t; ++i) offsets[i] = static_cast<int64_t>(4 * i);
    AppendValues(out, offsets.data(), offsets.size(), binary);
    out += "CONNECTIVITY vtktypeint64\n";
    std::vector<int64_t> connectivity(4 * t);
    for (size_t i = 0; i < t; ++i) {
      for (int k = 0; k < 4; ++k) connectivity[4 * i + k] = mesh.tets[i][k];
    }
    AppendValues(out, connectivity.data(), connectivity.size(), binary);
  } else {
    absl::StrAppend(&out, "CELLS ", t, " ", 5 * t, "\n");
    if (binary) {
      std::vector<int32_t> cells(5 * t);
      for (size_t i = 0; i < t; ++i) {
        cells[5 * i] = 4;
        for (int k = 0; k < 4; ++k) cells[5 * i + 1 + k] = static_cast<int32_t>(mesh.tets[i][k]);
      }
      AppendValues(out, cells.data(), cells.size(), true);
    } else {
      for (const Tet& tet : mesh.tets) {
        absl::StrAppend(&out, "4 ", tet[0], " ", tet[1], " ", tet[2], " ", tet[3], "\n");
      }
    }
  }
  absl::StrAppend(&out, "CELL_TYPES ", t, "\n");
  const std::vector<int32_t> types(t, kVtkTetra);
  AppendValues(out, types.data(), t, binary);
  if (!mesh.values.empty()) {
    absl::StrAppend(&out, "POINT_DATA ", v, "\nSCALARS value double 1\nLOOKUP_TABLE default\n");
    AppendValues(out, mesh.values.data(), v, binary);
  }
  // The first cell array as the section's SCALARS, the others in a FIELD, as
  // vtkUnstructuredGridWriter stores arrays beyond the active ones: VTK's legacy readers load
  // only the first SCALARS of a section unless told to read them all (ReadAllScalarsOn), so a
  // second SCALARS block was lost to them, and with it the region labels.
  struct CellArray {
    std::string name;
    const char* type;
    std::function<void()> append;
  };
  std::vector<CellArray> cell_arrays;
  if (!file.tet_iteration.empty()) {
    cell_arrays.push_back(
        {"iteration", "int", [&] { AppendValues(out, file.tet_iteration.data(), t, binary); }});
  }
  if (!file.tet_quality.empty()) {
    cell_arrays.push_back(
        {"quality", "float", [&] { AppendValues(out, file.tet_quality.data(), t, binary); }});
  }
  if (!file.mesh.labels.empty()) {
    cell_arrays.push_back({Escape(LabelArrayName(file)), "int",
                           [&] { AppendValues(out, file.mesh.labels.data(), t, binary); }});
  }
  if (!cell_arrays.empty()) {
    absl::StrAppend(&out, "CELL_DATA ", t, "\nSCALARS ", cell_arrays[0].name, " ",
                    cell_arrays[0].type, " 1\nLOOKUP_TABLE default\n");
    cell_arrays[0].append();
    if (cell_arrays.size() > 1) {
      absl::StrAppend(&out, "FIELD FieldData ", cell_arrays.size() - 1, "\n");
      for (size_t a = 1; a < cell_arrays.size(); ++a) {
        absl::StrAppend(&out, cell_arrays[a].name, " 1 ", t, " ", cell_arrays[a].type, "\n");
        cell_arrays[a].append();
      }
    }
  }
  return out;
}

}  // namespace tetrefine::io
