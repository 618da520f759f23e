#include "client/io/nrrd_reader.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <map>
#include <optional>
#include <type_traits>
#include <utility>
#include <vector>

#include "absl/strings/ascii.h"
#include "absl/strings/match.h"
#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_split.h"
#include "absl/strings/strip.h"
#include "client/io/file_bytes.h"
#include "client/io/grid_placement.h"
#include "client/io/header_lines.h"
#include "client/io/io_error.h"
#include "client/io/number_text.h"
#include "client/io/text_scanner.h"
#include "client/io/voxel_decode.h"
#include "client/io/world_frame.h"
#include "client/io/zlib_codec.h"

namespace tetrefine::io {
namespace {

// Every spelling of a type teem takes (nrrd/enumsNrrd.c, _nrrdTypeStrEqv; not "char" alone,
// whose sign C leaves open), in any case. int8, uint32, int64 and uint64 widen exactly
// (DecodeVoxels).
std::optional<StoredType> NrrdType(absl::string_view name) {
  static const auto* const kTypes = new std::map<absl::string_view, StoredType>{
      {"signed char", StoredType::kInt8},
      {"int8", StoredType::kInt8},
      {"int8_t", StoredType::kInt8},
      {"uchar", StoredType::kUint8},
      {"unsigned char", StoredType::kUint8},
      {"uint8", StoredType::kUint8},
      {"uint8_t", StoredType::kUint8},
      {"short", StoredType::kInt16},
      {"short int", StoredType::kInt16},
      {"signed short", StoredType::kInt16},
      {"signed short int", StoredType::kInt16},
      {"int16", StoredType::kInt16},
      {"int16_t", StoredType::kInt16},
      {"ushort", StoredType::kUint16},
      {"unsigned short", StoredType::kUint16},
      {"unsigned short int", StoredType::kUint16},
      {"uint16", StoredType::kUint16},
      {"uint16_t", StoredType::kUint16},
      {"int", StoredType::kInt32},
      {"signed int", StoredType::kInt32},
      {"int32", StoredType::kInt32},
      {"int32_t", StoredType::kInt32},
      {"uint", StoredType::kUint32},
      {"unsigned int", StoredType::kUint32},
      {"uint32", StoredType::kUint32},
      {"uint32_t", StoredType::kUint32},
      {"longlong", StoredType::kInt64},
      {"long long", StoredType::kInt64},
      {"long long int", StoredType::kInt64},
      {"signed long long", StoredType::kInt64},
      {"signed long long int", StoredType::kInt64},
      {"int64", StoredType::kInt64},
      {"int64_t", StoredType::kInt64},
      {"ulonglong", StoredType::kUint64},
      {"unsigned long long", StoredType::kUint64},
      {"unsigned long long int", StoredType::kUint64},
      {"uint64", StoredType::kUint64},
      {"uint64_t", StoredType::kUint64},
      {"float", StoredType::kFloat32},
      {"double", StoredType::kFloat64},
  };
  const auto it = kTypes->find(absl::AsciiStrToLower(name));
  if (it == kTypes->end()) return std::nullopt;
  return it->second;
}

// Sign per world axis that turns the file's space into RAS; nullopt for an unsupported space.
std::optional<Vec3> RasSigns(absl::string_view space) {
  const std::string s = absl::AsciiStrToLower(space);
  if (s == "right-anterior-superior" || s == "ras") return Vec3{1, 1, 1};
  if (s == "left-anterior-superior" || s == "las") return Vec3{-1, 1, 1};
  if (s == "left-posterior-superior" || s == "lps") return Vec3{-1, -1, 1};
  // No anatomical meaning stated: read as ITK reads them (and so 3D Slicer), as its LPS physical
  // coordinates, like a MetaImage's. They were kept as RAS, so the same grid read from an .mhd
  // and from such a .nrrd lay mirrored in x and y (an outside review, 2026-11-28).
  if (s == "scanner-xyz" || s == "3d-right-handed" || s == "3d-left-handed") return Vec3{-1, -1, 1};
  return std::nullopt;
}

// Parses "(a,b,c)" into a vector; false on anything else.
bool ParseVector(absl::string_view text, Vec3& v) {
  text = absl::StripAsciiWhitespace(text);
  if (!absl::ConsumePrefix(&text, "(") || !absl::ConsumeSuffix(&text, ")")) return false;
  const std::vector<absl::string_view> parts = absl::StrSplit(text, ',');
  if (parts.size() != 3) return false;
  for (int i = 0; i < 3; ++i) {
    if (!ParseDouble(absl::StripAsciiWhitespace(parts[i]), v[i]) || !std::isfinite(v[i])) {
      return false;
    }
  }
  return true;
}

std::vector<absl::string_view> Words(absl::string_view text) {
  return absl::StrSplit(text, absl::ByAnyChar(" \t"), absl::SkipEmpty());
}

// The field names teem's NRRD reader (nrrd/enumsNrrd.c, _nrrdFieldStrEqv) takes as another
// spelling of a field, without the space. A reader that looked up only the spaced names read
// such a file wrong without a word: `byteskip` was ignored (every voxel shifted), `spaceorigin`
// and `spacedirections` gave a grid at 0 with 1 mm voxels (found 2026-11-28 with files written to
// the spec; tests/io/volume_formats_test.cc IoNrrdTest.TeemsOtherFieldSpellingsAreRead).
absl::string_view CanonicalFieldName(absl::string_view lower_case_name) {
  static const auto* const kSpellings = new std::map<absl::string_view, absl::string_view>{
      {"blocksize", "block size"},
      {"spacedimension", "space dimension"},
      {"axismins", "axis mins"},
      {"axismaxs", "axis maxs"},
      {"spacedirections", "space directions"},
      {"centerings", "centers"},
      {"oldmin", "old min"},
      {"oldmax", "old max"},
      {"lineskip", "line skip"},
      {"byteskip", "byte skip"},
      {"sampleunits", "sample units"},
      {"spaceunits", "space units"},
      {"spaceorigin", "space origin"},
      {"measurementframe", "measurement frame"},
      {"datafile", "data file"},
  };
  const auto it = kSpellings->find(lower_case_name);
  return it == kSpellings->end() ? lower_case_name : it->second;
}

// The vectors of "space directions": "(x,y,z)" groups (teem reads spaces inside one, as in
// "(1.5, 0, 0)") or words such as "none", in order. An unclosed "(" runs to the end.
std::vector<absl::string_view> SpaceVectors(absl::string_view text) {
  std::vector<absl::string_view> vectors;
  size_t i = 0;
  while (i < text.size()) {
    if (text[i] == ' ' || text[i] == '\t') {
      ++i;
      continue;
    }
    const size_t end = text[i] == '(' ? std::min(text.find(')', i), text.size() - 1) + 1
                                      : text.find_first_of(" \t", i);
    const size_t stop = end == absl::string_view::npos ? text.size() : end;
    vectors.push_back(text.substr(i, stop - i));
    i = stop;
  }
  return vectors;
}

struct NrrdFields {
  std::map<std::string, std::string> values;  // field name (lower case) -> value
  size_t data_offset = 0;                     // first byte after the header's blank line
};

absl::StatusOr<NrrdFields> ParseNrrdHeader(absl::string_view bytes, const std::string& path) {
  HeaderLines lines(bytes);
  absl::string_view line;
  if (!lines.Next(line) || !absl::StartsWith(line, "NRRD000")) {
    return FileError(path, "not a NRRD file: first line is not NRRD000<version>");
  }
  NrrdFields fields;
  bool blank_seen = false;
  while (lines.Next(line)) {
    if (line.empty()) {
      blank_seen = true;
      break;
    }
    if (line[0] == '#') continue;
    if (absl::StrContains(line, ":=")) continue;  // key/value pair: free-form metadata
    const size_t colon = line.find(": ");
    if (colon == absl::string_view::npos) {
      return FileLineError(path, lines.line_number(),
                           absl::StrCat("expected \"field: value\", got ", QuoteToken(line)));
    }
    const std::string written = absl::AsciiStrToLower(line.substr(0, colon));
    const std::string name(CanonicalFieldName(written));
    const std::string value(absl::StripAsciiWhitespace(line.substr(colon + 2)));
    if (!fields.values.emplace(name, value).second) {
      return FileLineError(path, lines.line_number(),
                           absl::StrCat("field \"", written, "\" is given twice"));
    }
    // "data file: LIST": the header's remaining lines name the data files, one a line.
    if (name == "data file" && absl::StartsWith(value, "LIST")) break;
  }
  fields.data_offset = lines.offset();
  const bool detached = fields.values.count("data file") > 0;
  if (!blank_seen && !detached) {
    return FileError(path, "truncated: header has no blank line before the data");
  }
  return fields;
}

absl::string_view Field(const NrrdFields& fields, const std::string& name) {
  const auto it = fields.values.find(name);
  return it == fields.values.end() ? absl::string_view() : absl::string_view(it->second);
}

template <typename T>
bool AppendIfFits(std::string& out, double value) {
  if constexpr (std::is_integral_v<T>) {
    // The largest int64 and uint64 round up to 2^63 and 2^64 as doubles, which do not fit.
    constexpr double kMax = static_cast<double>(std::numeric_limits<T>::max());
    if (!(value >= static_cast<double>(std::numeric_limits<T>::min()) &&
          (sizeof(T) < 8 ? value <= kMax : value < kMax))) {
      return false;
    }
  }
  AppendLittle(out, static_cast<T>(value));
  return true;
}

// Appends `value` as a little-endian `type`; false when it does not fit.
bool AppendSample(std::string& out, StoredType type, double value) {
  switch (type) {
    case StoredType::kUint8:
      return AppendIfFits<uint8_t>(out, value);
    case StoredType::kInt16:
      return AppendIfFits<int16_t>(out, value);
    case StoredType::kUint16:
      return AppendIfFits<uint16_t>(out, value);
    case StoredType::kInt32:
      return AppendIfFits<int32_t>(out, value);
    case StoredType::kFloat32:
      return AppendIfFits<float>(out, value);
    case StoredType::kFloat64:
      return AppendIfFits<double>(out, value);
    case StoredType::kInt8:
      return AppendIfFits<int8_t>(out, value);
    case StoredType::kUint32:
      return AppendIfFits<uint32_t>(out, value);
    case StoredType::kInt64:
      return AppendIfFits<int64_t>(out, value);
    case StoredType::kUint64:
      return AppendIfFits<uint64_t>(out, value);
  }
  return false;
}

// Appends a 64-bit integer sample written as an integer, exactly (a double would round one
// beyond 2^53); false for any other word, which then goes the way of the other types.
bool AppendExactInteger(std::string& out, StoredType type, absl::string_view word) {
  if (type == StoredType::kInt64) {
    int64_t value;
    if (!absl::SimpleAtoi(word, &value)) return false;
    AppendLittle(out, value);
    return true;
  }
  if (type == StoredType::kUint64) {
    uint64_t value;
    if (!absl::SimpleAtoi(word, &value)) return false;
    AppendLittle(out, value);
    return true;
  }
  return false;
}

absl::StatusOr<std::string> DecodeAscii(absl::string_view text, StoredType type, uint64_t count,
                                        absl::string_view path) {
  std::string out;
  out.reserve(std::min<uint64_t>(count, text.size()) * StoredSize(type));
  uint64_t seen = 0;
  for (absl::string_view word :
       absl::StrSplit(text, absl::ByAnyChar(" \t\r\n,"), absl::SkipEmpty())) {
    if (seen == count) break;
    if (AppendExactInteger(out, type, word)) {
      ++seen;
      continue;
    }
    double value;
    if (!ParseDouble(word, value)) {
      return FileError(path, absl::StrCat("ascii sample ", seen, " is not a number: \"",
                                          word.substr(0, 32), "\""));
    }
    // "3.5" in an integer volume was stored as 3 (the conversion truncates): a writer that put
    // fractions in an integer file is not to be second-guessed. Whole numbers in any notation
    // ("3.0", "3e2") are read as the integers they are.
    if (type != StoredType::kFloat32 && type != StoredType::kFloat64 && std::isfinite(value) &&
        value != std::floor(value)) {
      return FileError(
          path, absl::StrCat("ascii sample ", seen, " = ", word.substr(0, 32),
                             " is not a whole number, as type ", StoredTypeName(type), " needs"));
    }
    if (!AppendSample(out, type, value)) {
      return FileError(path, absl::StrCat("ascii sample ", seen, " = ", word.substr(0, 32),
                                          " does not fit type ", StoredTypeName(type)));
    }
    ++seen;
  }
  if (seen < count) {
    return FileError(path, absl::StrCat("truncated: header says ", count,
                                        " ascii samples, file "
                                        "has ",
                                        seen));
  }
  return out;
}

}  // namespace

absl::StatusOr<VolumeFile> ReadNrrd(const std::string& path) {
  absl::StatusOr<std::string> file = ReadFileBytes(path);
  if (!file.ok()) return file.status();
  absl::StatusOr<NrrdFields> fields = ParseNrrdHeader(*file, path);
  if (!fields.ok()) return fields.status();

  const absl::string_view type_name = Field(*fields, "type");
  const std::optional<StoredType> type = NrrdType(type_name);
  if (!type.has_value()) {
    return FileUnsupported(path, absl::StrCat("NRRD type \"", type_name,
                                              "\" is not supported; "
                                              "supported: int8, uchar, short, ushort, int, uint, "
                                              "longlong, ulonglong, float, double"));
  }
  // A 4D file with one axis of a single sample that is not in space (its space direction
  // "none", or no space directions at all) is a 3D volume: what pynrrd and 3D Slicer write for a
  // one-component vector volume ("kinds: list domain domain domain"). NIfTI's singleton fourth
  // axis is read the same way.
  std::vector<absl::string_view> sizes = Words(Field(*fields, "sizes"));
  std::vector<absl::string_view> vectors = SpaceVectors(Field(*fields, "space directions"));
  std::vector<absl::string_view> spacings = Words(Field(*fields, "spacings"));
  const absl::string_view dimension = Field(*fields, "dimension");
  if (dimension == "4" && sizes.size() == 4) {
    int single = -1;
    for (int a = 0; a < 4; ++a) {
      const bool in_space = vectors.size() == 4 && vectors[a] != "none";
      if (sizes[a] == "1" && !in_space && single < 0) single = a;
    }
    if (single < 0) {
      return FileUnsupported(path,
                             "dimension \"4\" with no non-spatial axis of size 1: only 3D "
                             "volumes are read (one scalar a voxel)");
    }
    sizes.erase(sizes.begin() + single);
    if (vectors.size() == 4) vectors.erase(vectors.begin() + single);
    if (spacings.size() == 4) spacings.erase(spacings.begin() + single);
  } else if (dimension != "3") {
    return FileUnsupported(path,
                           absl::StrCat("dimension \"", dimension, "\": only 3D volumes are read"));
  }
  if (sizes.size() != 3) return FileError(path, "\"sizes\" must give 3 sizes");
  Index3 dims;
  for (int a = 0; a < 3; ++a) {
    if (!ParseInt64(sizes[a], dims[a]) || dims[a] < 1 || dims[a] > kMaxVolumeAxis) {
      return FileError(path, absl::StrCat("size \"", sizes[a], "\" must be in [1, 2^20]"));
    }
  }

  std::array<Vec3, 3> axes{};
  std::vector<std::string> spacing_warnings;
  Vec3 origin{0, 0, 0};
  // Without "space" too, as ITK reads such a file: LPS (see RasSigns).
  Vec3 signs{-1, -1, 1};
  if (const absl::string_view space = Field(*fields, "space"); !space.empty()) {
    const std::optional<Vec3> ras = RasSigns(space);
    if (!ras.has_value()) {
      return FileUnsupported(path, absl::StrCat("space \"", space, "\" is not supported"));
    }
    signs = *ras;
  }
  if (!Field(*fields, "space directions").empty()) {
    if (vectors.size() != 3) return FileError(path, "\"space directions\" must give 3 vectors");
    for (int a = 0; a < 3; ++a) {
      if (!ParseVector(vectors[a], axes[a])) {
        return FileError(path, absl::StrCat("space direction \"", vectors[a],
                                            "\" is not a finite (x,y,z) vector"));
      }
    }
    if (const absl::string_view o = Field(*fields, "space origin"); !o.empty()) {
      if (!ParseVector(o, origin)) {
        return FileError(path, absl::StrCat("space origin \"", o, "\" is not a finite (x,y,z)"));
      }
    }
  } else {
    for (int a = 0; a < 3; ++a) {
      double step = 1.0;
      if (a < static_cast<int>(spacings.size()) && ParseDouble(spacings[a], step) &&
          std::isfinite(step) && step != 0.0) {
        step = std::abs(step);
      } else {
        // "nan" (NRRD's unknown), 0 or absent: 1, said (as the NIfTI reader says a zero pixdim),
        // since every distance in the result then depends on it.
        spacing_warnings.push_back(absl::StrCat(
            path, ": ",
            a < static_cast<int>(spacings.size())
                ? absl::StrCat("spacing \"", spacings[a], "\" of axis ", a, " is not a size")
                : absl::StrCat("no spacing for axis ", a),
            " and the file has no space directions: voxel size 1 used along axis ", a));
        step = 1.0;
      }
      axes[a][a] = step;
    }
    // "axis mins" place the grid, as ITK's reader (NrrdIO's nrrdOriginCalculate) places it: the
    // first sample at the min for node-centred axes, half a sample in for cell-centred ones (the
    // default when "centers" does not say). They were ignored: every such grid began at 0.
    const std::vector<absl::string_view> mins = Words(Field(*fields, "axis mins"));
    const std::vector<absl::string_view> centers = Words(Field(*fields, "centers"));
    // A "nan" (NRRD's unknown) leaves the grid at 0, as ITK leaves it.
    std::array<double, 3> min{};
    bool known = mins.size() == 3;
    for (int a = 0; a < 3 && known; ++a) {
      known = ParseDouble(mins[a], min[a]) && std::isfinite(min[a]);
    }
    for (int a = 0; a < 3 && known; ++a) {
      const bool node =
          a < static_cast<int>(centers.size()) && absl::AsciiStrToLower(centers[a]) == "node";
      origin[a] = node ? min[a] : min[a] + 0.5 * axes[a][a];
    }
  }
  Affine affine = AffineFromAxes(axes, origin);
  for (int row = 0; row < 3; ++row) {
    for (int column = 0; column < 4; ++column) affine[row][column] *= signs[row];
  }

  // Locate the (possibly detached) payload.
  std::string detached_storage;
  absl::string_view payload = absl::string_view(*file).substr(fields->data_offset);
  std::string data_path = path;
  const absl::string_view data_file = Field(*fields, "data file");
  if (!data_file.empty()) {
    if (absl::StartsWith(data_file, "LIST") || Words(data_file).size() > 1) {
      return FileUnsupported(path, "multi-file NRRD data (LIST or pattern) is not supported");
    }
    std::filesystem::path p(std::string{data_file});
    if (p.is_relative()) p = std::filesystem::path(path).parent_path() / p;
    data_path = p.string();
    absl::StatusOr<std::string> bytes = ReadFileBytes(data_path);
    if (!bytes.ok()) return WithPath(path, bytes.status());
    detached_storage = *std::move(bytes);
    payload = detached_storage;
  }
  int64_t line_skip = 0;
  if (const absl::string_view s = Field(*fields, "line skip"); !s.empty()) {
    if (!ParseInt64(s, line_skip) || line_skip < 0) return FileError(path, "bad \"line skip\"");
  }
  for (int64_t i = 0; i < line_skip; ++i) {
    const size_t end = payload.find('\n');
    if (end == absl::string_view::npos) {
      return FileError(data_path, "truncated: fewer lines than \"line skip\"");
    }
    payload.remove_prefix(end + 1);
  }

  const std::string encoding = absl::AsciiStrToLower(Field(*fields, "encoding"));
  const uint64_t count = static_cast<uint64_t>(dims[0]) * static_cast<uint64_t>(dims[1]) *
                         static_cast<uint64_t>(dims[2]);
  const uint64_t need = count * StoredSize(*type);
  std::string decoded;
  if (encoding == "gzip" || encoding == "gz") {
    absl::StatusOr<std::string> inflated = Inflate(payload);
    if (!inflated.ok()) return WithPath(data_path, inflated.status());
    decoded = *std::move(inflated);
    payload = decoded;
  } else if (encoding == "ascii" || encoding == "text" || encoding == "txt") {
    absl::StatusOr<std::string> values = DecodeAscii(payload, *type, count, data_path);
    if (!values.ok()) return values.status();
    decoded = *std::move(values);
    payload = decoded;
  } else if (encoding != "raw") {
    return FileUnsupported(path, absl::StrCat("encoding \"", encoding,
                                              "\" is not supported; "
                                              "supported: raw, gzip, ascii"));
  }
  int64_t byte_skip = 0;
  if (const absl::string_view s = Field(*fields, "byte skip"); !s.empty()) {
    if (!ParseInt64(s, byte_skip) || byte_skip < -1) return FileError(path, "bad \"byte skip\"");
  }
  if (byte_skip == -1) {
    // -1: the samples are the last bytes of the payload.
    byte_skip = payload.size() >= need ? static_cast<int64_t>(payload.size() - need) : 0;
  }
  const uint64_t have =
      payload.size() > static_cast<uint64_t>(byte_skip) ? payload.size() - byte_skip : 0;
  if (have < need) {
    return FileError(data_path, absl::StrCat("truncated: header says ", need,
                                             " voxel bytes, "
                                             "file has ",
                                             have));
  }
  ByteOrder order = ByteOrder::kLittle;
  if (absl::AsciiStrToLower(Field(*fields, "endian")) == "big" && encoding != "ascii" &&
      encoding != "text" && encoding != "txt") {
    order = ByteOrder::kBig;
  }
  absl::StatusOr<DecodedVoxels> voxels =
      DecodeVoxels(payload.substr(byte_skip, need), *type, order, 0.0, 0.0);
  if (!voxels.ok()) return WithPath(path, voxels.status());
  absl::StatusOr<VolumeFile> placed =
      PlaceOnGrid(path, affine, dims, voxels->type, std::move(voxels->data));
  if (placed.ok()) {
    placed->warnings.insert(placed->warnings.end(), spacing_warnings.begin(),
                            spacing_warnings.end());
  }
  return placed;
}

}  // namespace tetrefine::io
