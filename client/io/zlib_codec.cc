#include "client/io/zlib_codec.h"

#include <zlib.h>

#include <algorithm>
#include <limits>

#include "absl/status/status.h"
#include "absl/strings/str_cat.h"

namespace tetrefine::io {
namespace {

// zlib counts in uInt; feed at most this much per call so multi-gigabyte buffers work.
constexpr size_t kMaxChunk = size_t{1} << 30;

absl::Status ZlibError(absl::string_view what, const z_stream& stream, int code) {
  return absl::InvalidArgumentError(absl::StrCat(
      what, ": ", stream.msg != nullptr ? stream.msg : zError(code), " (zlib code ", code, ")"));
}

// Inflates with the given windowBits into `out`, until the stream ends or `limit` bytes are out.
absl::Status InflateInto(absl::string_view compressed, int window_bits, size_t limit,
                         std::string& out) {
  z_stream stream{};
  int code = inflateInit2(&stream, window_bits);
  if (code != Z_OK) return ZlibError("inflateInit2 failed", stream, code);
  size_t consumed = 0;
  char buffer[1 << 16];
  while (true) {
    if (stream.avail_in == 0 && consumed < compressed.size()) {
      const size_t chunk = std::min(kMaxChunk, compressed.size() - consumed);
      stream.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(compressed.data() + consumed));
      stream.avail_in = static_cast<uInt>(chunk);
      consumed += chunk;
    }
    stream.next_out = reinterpret_cast<Bytef*>(buffer);
    stream.avail_out = sizeof(buffer);
    code = inflate(&stream, Z_NO_FLUSH);
    const size_t produced = sizeof(buffer) - stream.avail_out;
    if (out.size() + produced > limit) {
      inflateEnd(&stream);
      return absl::InvalidArgumentError(
          absl::StrCat("compressed data decodes to more than the expected ", limit, " bytes"));
    }
    out.append(buffer, produced);
    if (code == Z_STREAM_END) {
      // A gzip file may hold several members; gunzip concatenates them.
      const size_t rest = stream.avail_in + (compressed.size() - consumed);
      const absl::string_view tail = compressed.substr(compressed.size() - rest);
      if (window_bits > 15 && IsGzip(tail)) {
        inflateReset(&stream);
        continue;
      }
      break;
    }
    if (code == Z_BUF_ERROR && stream.avail_in == 0 && consumed == compressed.size()) {
      inflateEnd(&stream);
      return absl::InvalidArgumentError(
          absl::StrCat("compressed data is truncated (", out.size(), " bytes decoded)"));
    }
    if (code != Z_OK && code != Z_BUF_ERROR) {
      const absl::Status status = ZlibError("corrupt compressed data", stream, code);
      inflateEnd(&stream);
      return status;
    }
  }
  inflateEnd(&stream);
  return absl::OkStatus();
}

}  // namespace

bool IsGzip(absl::string_view bytes) {
  return bytes.size() >= 2 && static_cast<unsigned char>(bytes[0]) == 0x1f &&
         static_cast<unsigned char>(bytes[1]) == 0x8b;
}

absl::StatusOr<std::string> Inflate(absl::string_view compressed) {
  std::string out;
  // 15 + 32: accept both zlib and gzip headers.
  absl::Status status = InflateInto(compressed, 15 + 32, std::numeric_limits<size_t>::max(), out);
  if (!status.ok()) return status;
  return out;
}

absl::StatusOr<std::string> InflateExact(absl::string_view compressed, size_t decoded_size) {
  std::string out;
  out.reserve(decoded_size);
  absl::Status status = InflateInto(compressed, 15 + 32, decoded_size, out);
  if (!status.ok()) return status;
  if (out.size() != decoded_size) {
    return absl::InvalidArgumentError(
        absl::StrCat("compressed data decodes to ", out.size(), " bytes, expected ", decoded_size));
  }
  return out;
}

absl::StatusOr<std::string> GzipCompress(absl::string_view data) {
  z_stream stream{};
  // 15 + 16: gzip wrapper; level 6 is gzip's default trade-off.
  int code = deflateInit2(&stream, 6, Z_DEFLATED, 15 + 16, 8, Z_DEFAULT_STRATEGY);
  if (code != Z_OK) return ZlibError("deflateInit2 failed", stream, code);
  std::string out;
  size_t consumed = 0;
  char buffer[1 << 16];
  do {
    if (stream.avail_in == 0 && consumed < data.size()) {
      const size_t chunk = std::min(kMaxChunk, data.size() - consumed);
      stream.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(data.data() + consumed));
      stream.avail_in = static_cast<uInt>(chunk);
      consumed += chunk;
    }
    const int flush = consumed == data.size() ? Z_FINISH : Z_NO_FLUSH;
    stream.next_out = reinterpret_cast<Bytef*>(buffer);
    stream.avail_out = sizeof(buffer);
    code = deflate(&stream, flush);
    if (code == Z_STREAM_ERROR) {
      deflateEnd(&stream);
      return absl::InternalError("deflate failed");
    }
    out.append(buffer, sizeof(buffer) - stream.avail_out);
  } while (code != Z_STREAM_END);
  deflateEnd(&stream);
  return out;
}

}  // namespace tetrefine::io
