#include "client/io/vtu_data_array.h"

#include <tbb/parallel_for.h>

#include <charconv>
#include <cstring>
#include <optional>
#include <utility>

#include "absl/strings/str_cat.h"
#include "client/io/byte_stream.h"
#include "client/io/io_error.h"
#include "client/io/number_text.h"
#include "client/io/vtk_scalar.h"
#include "core/huge_pages.h"

namespace tetrefine::io {
namespace {

// Counts beyond this are corrupt whatever the file: 2^56 values of 8 bytes overflow int64 bytes.
constexpr uint64_t kMaxValues = uint64_t{1} << 56;

bool IsSpace(char c) { return c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\f'; }

// The element's own character data, without child elements (VTK puts <InformationKey> elements
// inside DataArrays, after the values). One piece is viewed in place; several are joined.
class OwnText {
 public:
  explicit OwnText(pugi::xml_node node) {
    int pieces = 0;
    for (pugi::xml_node child : node.children()) {
      if (child.type() != pugi::node_pcdata && child.type() != pugi::node_cdata) continue;
      const absl::string_view piece(child.value());
      if (++pieces == 1) {
        view_ = piece;
      } else {
        if (pieces == 2) joined_.assign(view_.data(), view_.size());
        joined_.push_back(' ');
        joined_.append(piece.data(), piece.size());
        view_ = joined_;
      }
    }
  }
  absl::string_view view() const { return view_; }

 private:
  absl::string_view view_;
  std::string joined_;
};

// Parses whitespace-separated numbers; `parse` converts one token, returning false when it is
// not a valid value. Returns the index of a bad token (with `bad` set to it), or nullopt.
template <typename T, typename Parse>
absl::Status ParseTokens(absl::string_view text, uint64_t count, std::vector<T>& out, Parse parse,
                         const std::function<absl::Status(std::string)>& error) {
  // Each value takes at least two characters ("0 "), so a larger count is truncated or corrupt.
  if (count > text.size() / 2 + 1) {
    return error(absl::StrCat("needs ", count, " values but holds only ", text.size(),
                              " characters (truncated?)"));
  }
  ReserveHuge(out, count);
  out.resize(count);
  size_t pos = 0;
  uint64_t n = 0;
  while (true) {
    while (pos < text.size() && IsSpace(text[pos])) ++pos;
    if (pos >= text.size()) break;
    size_t end = pos;
    while (end < text.size() && !IsSpace(text[end])) ++end;
    const absl::string_view token = text.substr(pos, end - pos);
    if (n == count) return error(absl::StrCat("has more than the expected ", count, " values"));
    if (!parse(token, out[n])) {
      return error(
          absl::StrCat("value ", n, " is not a valid number here: \"", token.substr(0, 30), "\""));
    }
    ++n;
    pos = end;
  }
  if (n != count) return error(absl::StrCat("has ", n, " values, expected ", count));
  return absl::OkStatus();
}

}  // namespace

absl::Status VtuArrayReader::Error(pugi::xml_node array, absl::string_view problem) const {
  const pugi::xml_attribute name = array.attribute("Name");
  return FileLineError(
      path_, line_of_(array),
      absl::StrCat(array.name(), name ? absl::StrCat(" \"", name.value(), "\"") : "", " ",
                   problem));
}

uint64_t VtuArrayReader::HeaderWord(absl::string_view bytes, size_t index) const {
  const size_t offset = index * enc_.header_bytes;
  if (enc_.header_bytes == 8) return LoadAs<uint64_t>(bytes, offset, enc_.order);
  return LoadAs<uint32_t>(bytes, offset, enc_.order);
}

absl::StatusOr<std::string> VtuArrayReader::Bytes(pugi::xml_node array, int64_t expected) {
  const absl::string_view format = array.attribute("format").value();
  if (format == "binary") {
    const OwnText text(array);
    ByteStream in = ByteStream::Base64(text.view());
    return Decode(array, in, expected);
  }
  if (format == "appended") {
    if (!appended_.present) return Error(array, "is appended but the file has no <AppendedData>");
    int64_t offset = -1;
    if (!ParseInt64(array.attribute("offset").value(), offset) || offset < 0 ||
        static_cast<uint64_t>(offset) > appended_.data.size()) {
      return Error(array,
                   absl::StrCat("has a bad appended offset \"",
                                absl::string_view(array.attribute("offset").value()).substr(0, 30),
                                "\" (the appended data holds ", appended_.data.size(),
                                appended_.base64 ? " characters)" : " bytes)"));
    }
    const absl::string_view rest = appended_.data.substr(offset);
    ByteStream in = appended_.base64 ? ByteStream::Base64(rest) : ByteStream::Raw(rest);
    return Decode(array, in, expected);
  }
  return Error(array, absl::StrCat("has unknown format \"", format.substr(0, 30), "\""));
}

absl::StatusOr<std::string> VtuArrayReader::Decode(pugi::xml_node array, ByteStream& in,
                                                   int64_t expected) {
  const size_t h = enc_.header_bytes;
  const auto read = [&](size_t n, absl::string_view what) -> absl::StatusOr<absl::string_view> {
    absl::StatusOr<absl::string_view> bytes = in.Read(n);
    if (!bytes.ok()) return Error(array, absl::StrCat(what, ": ", bytes.status().message()));
    return bytes;
  };
  if (enc_.compressor == VtkCompressor::kNone) {
    absl::StatusOr<absl::string_view> head = read(h, "header");
    if (!head.ok()) return head.status();
    const uint64_t nbytes = HeaderWord(*head, 0);
    if (expected >= 0 && nbytes != static_cast<uint64_t>(expected)) {
      return Error(array, absl::StrCat("header says ", nbytes, " bytes, expected ", expected));
    }
    absl::StatusOr<absl::string_view> body = read(nbytes, "data");
    if (!body.ok()) return body.status();
    return std::string(*body);
  }
  absl::StatusOr<absl::string_view> head = read(3 * h, "compression header");
  if (!head.ok()) return head.status();
  const uint64_t blocks = HeaderWord(*head, 0);
  const uint64_t block_size = HeaderWord(*head, 1);
  const uint64_t last_size = HeaderWord(*head, 2);
  // Every block takes a header word and at least one byte.
  if (blocks > in.MaxRemaining() / (h + 1)) {
    return Error(array, absl::StrCat("compression header claims ", blocks,
                                     " blocks, more than the data can hold (corrupt)"));
  }
  if (blocks > 0 &&
      (block_size == 0 || block_size > (uint64_t{1} << 40) || last_size > block_size)) {
    return Error(array, absl::StrCat("has a corrupt compression header (block size ", block_size,
                                     ", last block ", last_size, ")"));
  }
  absl::StatusOr<absl::string_view> sizes_bytes = read(blocks * h, "block sizes");
  if (!sizes_bytes.ok()) return sizes_bytes.status();
  std::vector<uint64_t> compressed_size(blocks);
  std::vector<uint64_t> start(blocks + 1, 0);
  for (uint64_t b = 0; b < blocks; ++b) {
    compressed_size[b] = HeaderWord(*sizes_bytes, b);
    if (compressed_size[b] > in.MaxRemaining()) {
      return Error(array, absl::StrCat("block ", b, " claims ", compressed_size[b],
                                       " compressed bytes, more than remain (truncated?)"));
    }
    start[b + 1] = start[b] + compressed_size[b];
  }
  // Each block's claimed size must be within the compressor's reach of its compressed size;
  // checked before the total is formed, which bounds it by the file's size.
  const size_t expansion = MaxExpansion(enc_.compressor);
  const uint64_t last_decoded = last_size == 0 ? block_size : last_size;
  for (uint64_t b = 0; b < blocks; ++b) {
    const uint64_t decoded = b + 1 == blocks ? last_decoded : block_size;
    if (decoded > compressed_size[b] * expansion + 64) {
      return Error(array, absl::StrCat("block ", b, " claims ", decoded, " bytes from ",
                                       compressed_size[b], " compressed ones (corrupt)"));
    }
  }
  const uint64_t total = blocks == 0 ? 0 : (blocks - 1) * block_size + last_decoded;
  if (expected >= 0 && total != static_cast<uint64_t>(expected)) {
    return Error(array,
                 absl::StrCat("compression header says ", total, " bytes, expected ", expected));
  }
  absl::StatusOr<absl::string_view> data = read(start[blocks], "compressed data");
  if (!data.ok()) return data.status();
  std::string out;
  ReserveHuge(out, total);
  out.resize(total);
  // Blocks decode independently; the first failing block (by index) is reported.
  std::vector<absl::Status> failures(blocks);
  tbb::parallel_for(uint64_t{0}, blocks, [&](uint64_t b) {
    const uint64_t decoded = b + 1 == blocks ? last_decoded : block_size;
    failures[b] = DecompressBlock(enc_.compressor, data->substr(start[b], compressed_size[b]),
                                  out.data() + b * block_size, decoded);
  });
  for (uint64_t b = 0; b < blocks; ++b) {
    if (!failures[b].ok()) {
      return Error(array, absl::StrCat("block ", b, ": ", failures[b].message()));
    }
  }
  return out;
}

absl::StatusOr<std::vector<double>> VtuArrayReader::Doubles(pugi::xml_node array, uint64_t count) {
  const std::optional<VtkScalar> type = VtkScalarFromXml(array.attribute("type").value());
  if (!type) {
    return Error(array, absl::StrCat("has type \"", array.attribute("type").value(),
                                     "\", expected a numeric type"));
  }
  if (count > kMaxValues) return Error(array, "is too large");
  std::vector<double> out;
  const absl::string_view format = array.attribute("format").value();
  if (format.empty() || format == "ascii") {
    const OwnText text(array);
    absl::Status s = ParseTokens(
        text.view(), count, out, [](absl::string_view t, double& v) { return ParseDouble(t, v); },
        [&](std::string problem) { return Error(array, problem); });
    if (!s.ok()) return s;
    return out;
  }
  absl::StatusOr<std::string> bytes = Bytes(array, count * VtkScalarSize(*type));
  if (!bytes.ok()) return bytes.status();
  ReserveHuge(out, count);
  out.resize(count);
  ScalarsToDoubles(*bytes, *type, enc_.order, count, out.data());
  return out;
}

absl::StatusOr<std::vector<int64_t>> VtuArrayReader::Int64s(pugi::xml_node array, uint64_t count) {
  const std::optional<VtkScalar> type = VtkScalarFromXml(array.attribute("type").value());
  if (!type) {
    return Error(array, absl::StrCat("has type \"", array.attribute("type").value(),
                                     "\", expected a numeric type"));
  }
  if (count > kMaxValues) return Error(array, "is too large");
  std::vector<int64_t> out;
  const absl::string_view format = array.attribute("format").value();
  if (format.empty() || format == "ascii") {
    const OwnText text(array);
    const auto parse = [](absl::string_view t, int64_t& v) {
      if (ParseInt64(t, v)) return true;
      double d;
      if (!ParseDouble(t, d) || !(std::abs(d) < 0x1p62) || d != std::floor(d)) return false;
      v = static_cast<int64_t>(d);
      return true;
    };
    absl::Status s = ParseTokens(text.view(), count, out, parse,
                                 [&](std::string problem) { return Error(array, problem); });
    if (!s.ok()) return s;
    return out;
  }
  absl::StatusOr<std::string> bytes = Bytes(array, count * VtkScalarSize(*type));
  if (!bytes.ok()) return bytes.status();
  ReserveHuge(out, count);
  out.resize(count);
  const size_t bad = ScalarsToInt64s(*bytes, *type, enc_.order, count, out.data());
  if (bad != count) {
    // The value itself, not only its position: a float label array of 3.5s said "value 0".
    return Error(array, absl::StrCat("value ", bad, " is ",
                                     ScalarAt(*bytes, *type, enc_.order, bad), ", not an integer"));
  }
  return out;
}

absl::StatusOr<std::string> VtuArrayReader::StoredBytes(pugi::xml_node array, VtkScalar type,
                                                        uint64_t count) {
  if (count > kMaxValues) return Error(array, "is too large");
  return Bytes(array, static_cast<int64_t>(count * VtkScalarSize(type)));
}

absl::StatusOr<std::string> VtuArrayReader::StringBytes(pugi::xml_node array) {
  if (absl::string_view(array.attribute("type").value()) != "String") {
    return Error(array, "is not a String array");
  }
  const absl::string_view format = array.attribute("format").value();
  if (format.empty() || format == "ascii") {
    // Character codes as numbers: "76 80 83 0".
    const OwnText text(array);
    std::string out;
    size_t pos = 0;
    const absl::string_view t = text.view();
    while (pos < t.size()) {
      while (pos < t.size() && IsSpace(t[pos])) ++pos;
      size_t end = pos;
      while (end < t.size() && !IsSpace(t[end])) ++end;
      if (end == pos) break;
      int64_t code;
      if (!ParseInt64(t.substr(pos, end - pos), code) || code < 0 || code > 255) {
        return Error(array, "holds a character code outside 0-255");
      }
      out.push_back(static_cast<char>(code));
      pos = end;
    }
    return out;
  }
  return Bytes(array, -1);
}

}  // namespace tetrefine::io
