#include "client/io/metaimage_reader.h"

#include <cmath>
#include <filesystem>
#include <map>
#include <optional>
#include <utility>
#include <vector>

#include "absl/strings/ascii.h"
#include "absl/strings/match.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_split.h"
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

// MetaIO's element types (metaTypes.h). MET_LONG and MET_ULONG are 4 bytes on disk
// (MET_LONG_TYPE is int32_t, MET_ValueTypeSize 4) whatever the platform's long: ITK on LP64
// Linux writes an 8-byte `long` image as MET_LONG_LONG, and on Windows a 4-byte one as MET_LONG.
// int8, uint32, int64 and uint64 widen exactly (DecodeVoxels). MET_ASCII_CHAR (a char of
// unstated sign) stays refused.
std::optional<StoredType> MetaType(absl::string_view name) {
  if (name == "MET_CHAR") return StoredType::kInt8;
  if (name == "MET_UCHAR") return StoredType::kUint8;
  if (name == "MET_SHORT") return StoredType::kInt16;
  if (name == "MET_USHORT") return StoredType::kUint16;
  if (name == "MET_INT" || name == "MET_LONG") return StoredType::kInt32;
  if (name == "MET_UINT" || name == "MET_ULONG") return StoredType::kUint32;
  if (name == "MET_LONG_LONG") return StoredType::kInt64;
  if (name == "MET_ULONG_LONG") return StoredType::kUint64;
  if (name == "MET_FLOAT") return StoredType::kFloat32;
  if (name == "MET_DOUBLE") return StoredType::kFloat64;
  return std::nullopt;
}

bool IsTrue(absl::string_view value) { return absl::EqualsIgnoreCase(value, "true"); }

struct MetaHeader {
  std::map<std::string, std::string> values;  // key (lower case) -> value
  size_t data_offset = 0;                     // first byte after the ElementDataFile line
};

absl::StatusOr<MetaHeader> ParseMetaHeader(absl::string_view bytes, const std::string& path) {
  HeaderLines lines(bytes);
  absl::string_view line;
  MetaHeader header;
  while (lines.Next(line)) {
    const absl::string_view trimmed = absl::StripAsciiWhitespace(line);
    if (trimmed.empty()) continue;
    const size_t equals = trimmed.find('=');
    if (equals == absl::string_view::npos) {
      return FileLineError(
          path, lines.line_number(),
          // Quoted as tokens are: binary bytes went into the line raw (an outside review).
          absl::StrCat("expected \"Key = Value\", got ", QuoteToken(trimmed)));
    }
    const std::string key =
        absl::AsciiStrToLower(absl::StripAsciiWhitespace(trimmed.substr(0, equals)));
    header.values[key] = std::string(absl::StripAsciiWhitespace(trimmed.substr(equals + 1)));
    // ElementDataFile is always the last header line; binary data may follow it directly.
    if (key == "elementdatafile") {
      header.data_offset = lines.offset();
      return header;
    }
  }
  return FileError(path, "truncated or not a MetaImage: no ElementDataFile line");
}

absl::string_view Value(const MetaHeader& header, absl::string_view key) {
  const auto it = header.values.find(std::string(key));
  return it == header.values.end() ? absl::string_view() : absl::string_view(it->second);
}

// Parses exactly `n` finite numbers from the value of `key`; `fallback` when the key is absent.
absl::StatusOr<std::vector<double>> Numbers(const MetaHeader& header, absl::string_view key,
                                            size_t n, std::vector<double> fallback,
                                            absl::string_view path) {
  const absl::string_view text = Value(header, key);
  if (text.empty()) return fallback;
  std::vector<double> numbers;
  for (absl::string_view word : absl::StrSplit(text, absl::ByAnyChar(" \t"), absl::SkipEmpty())) {
    double value;
    if (!ParseDouble(word, value) || !std::isfinite(value)) {
      return FileError(path, absl::StrCat(key, ": \"", word, "\" is not a finite number"));
    }
    numbers.push_back(value);
  }
  if (numbers.size() != n) {
    return FileError(path, absl::StrCat(key, " has ", numbers.size(), " numbers, expected ", n));
  }
  return numbers;
}

// The first of `keys` present in the header, or the first key.
absl::string_view FirstPresent(const MetaHeader& header,
                               std::initializer_list<absl::string_view> keys) {
  for (absl::string_view key : keys) {
    if (!Value(header, key).empty()) return key;
  }
  return *keys.begin();
}

}  // namespace

absl::StatusOr<VolumeFile> ReadMetaImage(const std::string& path) {
  absl::StatusOr<std::string> file = ReadFileBytes(path);
  if (!file.ok()) return file.status();
  absl::StatusOr<MetaHeader> header = ParseMetaHeader(*file, path);
  if (!header.ok()) return header.status();

  if (const absl::string_view object = Value(*header, "objecttype");
      !object.empty() && !absl::EqualsIgnoreCase(object, "Image")) {
    return FileUnsupported(path, absl::StrCat("ObjectType \"", object, "\": only Image is read"));
  }
  if (Value(*header, "ndims") != "3") {
    return FileUnsupported(
        path, absl::StrCat("NDims \"", Value(*header, "ndims"), "\": only 3D volumes are read"));
  }
  if (const absl::string_view channels = Value(*header, "elementnumberofchannels");
      !channels.empty() && channels != "1") {
    return FileUnsupported(
        path, absl::StrCat("ElementNumberOfChannels ", channels, ": only scalar volumes are read"));
  }
  const absl::string_view type_name = Value(*header, "elementtype");
  const std::optional<StoredType> type = MetaType(type_name);
  if (!type.has_value()) {
    return FileUnsupported(path, absl::StrCat("ElementType \"", type_name,
                                              "\" is not supported; "
                                              "supported: MET_CHAR, MET_UCHAR, MET_SHORT, "
                                              "MET_USHORT, MET_INT, MET_UINT, MET_LONG, MET_ULONG, "
                                              "MET_LONG_LONG, MET_ULONG_LONG, MET_FLOAT, "
                                              "MET_DOUBLE"));
  }
  const absl::string_view binary = Value(*header, "binarydata");
  if (!binary.empty() && !IsTrue(binary)) {
    return FileUnsupported(path, "ASCII MetaImage data (BinaryData = False) is not supported");
  }

  absl::StatusOr<std::vector<double>> sizes = Numbers(*header, "dimsize", 3, {}, path);
  if (!sizes.ok()) return sizes.status();
  if (sizes->empty()) return FileError(path, "DimSize is missing");
  Index3 dims;
  for (int a = 0; a < 3; ++a) {
    const double s = (*sizes)[a];
    if (s != std::floor(s) || s < 1 || s > static_cast<double>(kMaxVolumeAxis)) {
      return FileError(path, absl::StrCat("DimSize ", s, " must be an integer in [1, 2^20]"));
    }
    dims[a] = static_cast<int64_t>(s);
  }
  absl::StatusOr<std::vector<double>> spacing = Numbers(
      *header, FirstPresent(*header, {"elementspacing", "elementsize"}), 3, {1, 1, 1}, path);
  if (!spacing.ok()) return spacing.status();
  absl::StatusOr<std::vector<double>> offset =
      Numbers(*header, FirstPresent(*header, {"offset", "origin", "position"}), 3, {0, 0, 0}, path);
  if (!offset.ok()) return offset.status();
  absl::StatusOr<std::vector<double>> matrix =
      Numbers(*header, FirstPresent(*header, {"transformmatrix", "rotation", "orientation"}), 9,
              {1, 0, 0, 0, 1, 0, 0, 0, 1}, path);
  if (!matrix.ok()) return matrix.status();

  std::array<Vec3, 3> axes;
  for (int a = 0; a < 3; ++a) {
    for (int w = 0; w < 3; ++w) axes[a][w] = (*matrix)[3 * a + w] * (*spacing)[a];
  }
  const Affine affine = LpsToRas(AffineFromAxes(axes, {(*offset)[0], (*offset)[1], (*offset)[2]}));

  // Locate the payload: LOCAL means right after the header.
  const absl::string_view data_file = Value(*header, "elementdatafile");
  std::string data_path = path;
  std::string detached;
  absl::string_view payload;
  if (absl::EqualsIgnoreCase(data_file, "LOCAL")) {
    payload = absl::string_view(*file).substr(header->data_offset);
  } else {
    if (absl::EqualsIgnoreCase(data_file, "LIST") || absl::StrContains(data_file, ' ')) {
      return FileUnsupported(path,
                             "multi-file MetaImage data (LIST or pattern) is not "
                             "supported");
    }
    std::filesystem::path p(std::string{data_file});
    if (p.is_relative()) p = std::filesystem::path(path).parent_path() / p;
    data_path = p.string();
    absl::StatusOr<std::string> bytes = ReadFileBytes(data_path);
    if (!bytes.ok()) return WithPath(path, bytes.status());
    detached = *std::move(bytes);
    payload = detached;
  }

  const uint64_t need = static_cast<uint64_t>(dims[0]) * static_cast<uint64_t>(dims[1]) *
                        static_cast<uint64_t>(dims[2]) * StoredSize(*type);
  std::string inflated;
  if (IsTrue(Value(*header, "compresseddata"))) {
    absl::StatusOr<std::string> out = InflateExact(payload, need);
    if (!out.ok()) return WithPath(data_path, out.status());
    inflated = *std::move(out);
    payload = inflated;
  } else if (const absl::string_view skip = Value(*header, "headersize"); !skip.empty()) {
    int64_t bytes = 0;
    if (!ParseInt64(skip, bytes) || bytes < -1) {
      return FileError(path, absl::StrCat("HeaderSize \"", skip, "\" is not a byte count"));
    }
    // -1: the samples are the last bytes of the data file.
    const uint64_t drop = bytes == -1 ? (payload.size() > need ? payload.size() - need : 0) : bytes;
    payload.remove_prefix(std::min<uint64_t>(drop, payload.size()));
  }
  if (payload.size() < need) {
    return FileError(data_path, absl::StrCat("truncated: header says ", need,
                                             " voxel bytes, file has ", payload.size()));
  }
  const bool msb = IsTrue(Value(*header, "binarydatabyteordermsb")) ||
                   IsTrue(Value(*header, "elementbyteordermsb"));
  absl::StatusOr<DecodedVoxels> voxels = DecodeVoxels(
      payload.substr(0, need), *type, msb ? ByteOrder::kBig : ByteOrder::kLittle, 0.0, 0.0);
  if (!voxels.ok()) return WithPath(path, voxels.status());
  return PlaceOnGrid(path, affine, dims, voxels->type, std::move(voxels->data));
}

}  // namespace tetrefine::io
