#include "client/io/vtk_compressor.h"

#include <lz4.h>
#include <lzma.h>
#include <zlib.h>

#include <algorithm>
#include <cstdint>
#include <limits>

#include "absl/strings/str_cat.h"

namespace tetrefine::io {
namespace {

absl::Status ZlibDecompress(absl::string_view compressed, char* out, size_t decoded_size) {
  // One call decodes the whole block: uInt counts limit a block to 4 GiB, which VTK's block
  // headers (a block size, not a file size) never approach; refuse rather than loop beyond.
  if (compressed.size() > std::numeric_limits<uInt>::max() ||
      decoded_size > std::numeric_limits<uInt>::max()) {
    return absl::InvalidArgumentError("zlib block larger than 4 GiB");
  }
  z_stream stream{};
  if (inflateInit(&stream) != Z_OK) return absl::InternalError("inflateInit failed");
  stream.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(compressed.data()));
  stream.avail_in = static_cast<uInt>(compressed.size());
  stream.next_out = reinterpret_cast<Bytef*>(out);
  stream.avail_out = static_cast<uInt>(decoded_size);
  const int code = inflate(&stream, Z_FINISH);
  const size_t produced = stream.total_out;
  std::string message = stream.msg != nullptr ? stream.msg : "";
  inflateEnd(&stream);
  if (code == Z_STREAM_END && produced == decoded_size) return absl::OkStatus();
  if (code == Z_BUF_ERROR && stream.avail_out == 0) {
    return absl::InvalidArgumentError(absl::StrCat("zlib block decodes to more than the ",
                                                   decoded_size, " bytes its header says"));
  }
  if (code == Z_BUF_ERROR || code == Z_STREAM_END) {
    return absl::InvalidArgumentError(
        absl::StrCat("zlib block decodes to ", produced, " bytes, its header says ", decoded_size));
  }
  return absl::InvalidArgumentError(
      absl::StrCat("corrupt zlib block: ", message.empty() ? zError(code) : message));
}

absl::Status LzmaDecompress(absl::string_view compressed, char* out, size_t decoded_size) {
  uint64_t memlimit = uint64_t{1} << 30;
  size_t in_pos = 0;
  size_t out_pos = 0;
  const lzma_ret code = lzma_stream_buffer_decode(
      &memlimit, 0, nullptr, reinterpret_cast<const uint8_t*>(compressed.data()), &in_pos,
      compressed.size(), reinterpret_cast<uint8_t*>(out), &out_pos, decoded_size);
  if (code == LZMA_OK && out_pos == decoded_size) return absl::OkStatus();
  if (code == LZMA_BUF_ERROR) {
    return absl::InvalidArgumentError(absl::StrCat(
        "lzma block is truncated or decodes to more than the ", decoded_size, " bytes expected"));
  }
  if (code == LZMA_OK) {
    return absl::InvalidArgumentError(
        absl::StrCat("lzma block decodes to ", out_pos, " bytes, expected ", decoded_size));
  }
  return absl::InvalidArgumentError(
      absl::StrCat("corrupt lzma (xz) block (liblzma code ", static_cast<int>(code), ")"));
}

absl::Status Lz4Decompress(absl::string_view compressed, char* out, size_t decoded_size) {
  if (compressed.size() > static_cast<size_t>(std::numeric_limits<int>::max()) ||
      decoded_size > static_cast<size_t>(std::numeric_limits<int>::max())) {
    return absl::InvalidArgumentError("lz4 block larger than 2 GiB");
  }
  const int produced = LZ4_decompress_safe(
      compressed.data(), out, static_cast<int>(compressed.size()), static_cast<int>(decoded_size));
  if (produced < 0) return absl::InvalidArgumentError("corrupt lz4 block");
  if (static_cast<size_t>(produced) != decoded_size) {
    return absl::InvalidArgumentError(
        absl::StrCat("lz4 block decodes to ", produced, " bytes, expected ", decoded_size));
  }
  return absl::OkStatus();
}

}  // namespace

std::optional<VtkCompressor> VtkCompressorFromName(absl::string_view name) {
  for (VtkCompressor c : {VtkCompressor::kZlib, VtkCompressor::kLzma, VtkCompressor::kLz4}) {
    if (name == VtkCompressorName(c)) return c;
  }
  return std::nullopt;
}

absl::string_view VtkCompressorName(VtkCompressor compressor) {
  switch (compressor) {
    case VtkCompressor::kZlib:
      return "vtkZLibDataCompressor";
    case VtkCompressor::kLzma:
      return "vtkLZMADataCompressor";
    case VtkCompressor::kLz4:
      return "vtkLZ4DataCompressor";
    case VtkCompressor::kNone:
      break;
  }
  return "";
}

size_t MaxExpansion(VtkCompressor compressor) {
  switch (compressor) {
    case VtkCompressor::kZlib:
      return 1100;
    case VtkCompressor::kLz4:
      return 260;
    case VtkCompressor::kLzma:
      return 8000;
    case VtkCompressor::kNone:
      break;
  }
  return 1;
}

absl::Status DecompressBlock(VtkCompressor compressor, absl::string_view compressed, char* out,
                             size_t decoded_size) {
  switch (compressor) {
    case VtkCompressor::kZlib:
      return ZlibDecompress(compressed, out, decoded_size);
    case VtkCompressor::kLzma:
      return LzmaDecompress(compressed, out, decoded_size);
    case VtkCompressor::kLz4:
      return Lz4Decompress(compressed, out, decoded_size);
    case VtkCompressor::kNone:
      break;
  }
  if (compressed.size() != decoded_size) {
    return absl::InvalidArgumentError(absl::StrCat("uncompressed block holds ", compressed.size(),
                                                   " bytes, expected ", decoded_size));
  }
  std::copy(compressed.begin(), compressed.end(), out);
  return absl::OkStatus();
}

void CompressBlock(VtkCompressor compressor, int level, absl::string_view raw, std::string& out) {
  const size_t start = out.size();
  switch (compressor) {
    case VtkCompressor::kZlib: {
      uLongf size = compressBound(static_cast<uLong>(raw.size()));
      out.resize(start + size);
      compress2(reinterpret_cast<Bytef*>(out.data() + start), &size,
                reinterpret_cast<const Bytef*>(raw.data()), static_cast<uLong>(raw.size()),
                std::clamp(level, 1, 9));
      out.resize(start + size);
      return;
    }
    case VtkCompressor::kLzma: {
      size_t size = lzma_stream_buffer_bound(raw.size());
      out.resize(start + size);
      size_t out_pos = 0;
      lzma_easy_buffer_encode(static_cast<uint32_t>(std::clamp(level, 0, 9)), LZMA_CHECK_CRC64,
                              nullptr, reinterpret_cast<const uint8_t*>(raw.data()), raw.size(),
                              reinterpret_cast<uint8_t*>(out.data() + start), &out_pos, size);
      out.resize(start + out_pos);
      return;
    }
    case VtkCompressor::kLz4: {
      const int bound = LZ4_compressBound(static_cast<int>(raw.size()));
      out.resize(start + bound);
      const int size =
          LZ4_compress_default(raw.data(), out.data() + start, static_cast<int>(raw.size()), bound);
      out.resize(start + size);
      return;
    }
    case VtkCompressor::kNone:
      break;
  }
  out.append(raw.data(), raw.size());
}

}  // namespace tetrefine::io
