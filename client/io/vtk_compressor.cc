#include "client/io/vtk_compressor.h"

#include <isa-l/igzip_lib.h>
#include <libdeflate.h>
#include <lz4.h>
#include <lzma.h>

#include <algorithm>
#include <bit>
#include <cstdint>
#include <limits>
#include <memory>
#include <new>
#include <stdexcept>
#include <vector>

#include "absl/strings/str_cat.h"

namespace tetrefine::io {
namespace {

// libdeflate decodes a zlib stream into a buffer of known size, about twice as fast as zlib's
// inflate; one decompressor per thread (they are not thread-safe, and cheap to keep).
absl::Status ZlibDecompress(absl::string_view compressed, char* out, size_t decoded_size) {
  struct Free {
    void operator()(libdeflate_decompressor* d) const { libdeflate_free_decompressor(d); }
  };
  thread_local std::unique_ptr<libdeflate_decompressor, Free> decompressor(
      libdeflate_alloc_decompressor());
  if (decompressor == nullptr) return absl::ResourceExhaustedError("cannot allocate a decoder");
  size_t produced = 0;
  const libdeflate_result result = libdeflate_zlib_decompress(
      decompressor.get(), compressed.data(), compressed.size(), out, decoded_size, &produced);
  switch (result) {
    case LIBDEFLATE_SUCCESS:
      if (produced == decoded_size) return absl::OkStatus();
      return absl::InvalidArgumentError(absl::StrCat("zlib block decodes to ", produced,
                                                     " bytes, its header says ", decoded_size));
    case LIBDEFLATE_INSUFFICIENT_SPACE:
      return absl::InvalidArgumentError(absl::StrCat("zlib block decodes to more than the ",
                                                     decoded_size, " bytes its header says"));
    default:
      return absl::InvalidArgumentError("corrupt or truncated zlib block");
  }
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

// One .xz stream per block, from an encoder kept between blocks. A fresh encoder per block
// (lzma_easy_buffer_encode) allocated, faulted in and freed its hash tables every time: a round
// trip of small meshes in 1000-byte blocks took 2.5 s against zlib's 37 ms (io_mesh_test's lzma
// cases; 17 s under the sanitizers). Re-initialising one lzma_stream reuses its memory when the
// filter options are unchanged, so only the tables' clearing is left.
struct BlockCompressor::LzmaCoder {
  lzma_stream stream = LZMA_STREAM_INIT;
  ~LzmaCoder() { lzma_end(&stream); }

  // Compresses `raw` into out[0 .. out.size()), which holds lzma_stream_buffer_bound(raw.size())
  // bytes; returns the compressed size.
  size_t Compress(int level, absl::string_view raw, std::string& out) {
    lzma_options_lzma options;
    if (lzma_lzma_preset(&options, static_cast<uint32_t>(std::clamp(level, 0, 9)))) {
      throw std::invalid_argument("lzma preset");
    }
    // A match never reaches back beyond the block, so a dictionary larger than the block gives
    // the same bytes, while its hash tables (cleared at every block) grow with it: the preset's
    // (1 MiB at level 1) is cut to the block, rounded up to a power of two so that full blocks
    // share one size and the memory is reused.
    const auto block = static_cast<uint32_t>(std::min<size_t>(raw.size(), size_t{1} << 30));
    options.dict_size =
        std::min(options.dict_size, std::max<uint32_t>(LZMA_DICT_SIZE_MIN, std::bit_ceil(block)));
    lzma_filter filters[] = {{LZMA_FILTER_LZMA2, &options}, {LZMA_VLI_UNKNOWN, nullptr}};
    // Only out of memory fails (the output holds the worst case); a block written short would
    // corrupt the file.
    if (lzma_stream_encoder(&stream, filters, LZMA_CHECK_CRC64) != LZMA_OK) throw std::bad_alloc();
    stream.next_in = reinterpret_cast<const uint8_t*>(raw.data());
    stream.avail_in = raw.size();
    stream.next_out = reinterpret_cast<uint8_t*>(out.data());
    stream.avail_out = out.size();
    const lzma_ret code = lzma_code(&stream, LZMA_FINISH);
    if (code != LZMA_STREAM_END) throw std::bad_alloc();
    return out.size() - stream.avail_out;
  }
};

// A zlib stream per block from ISA-L's igzip at its level 1, with a stream and level buffer kept
// between blocks.
struct BlockCompressor::IsalCoder {
  isal_zstream stream;
  std::vector<uint8_t> level_buffer = std::vector<uint8_t>(ISAL_DEF_LVL1_DEFAULT);

  // The most a block of n bytes can take: igzip falls back to stored blocks (5 bytes of header
  // per 64 KiB) after at most one Huffman header, inside zlib's 6 bytes.
  static size_t Bound(size_t n) { return n + n / 8 + ISAL_DEF_MAX_HDR_SIZE + 1024; }

  // Compresses `raw` into out[0 .. capacity); the compressed size, or 0 if igzip failed.
  size_t Compress(absl::string_view raw, char* out, size_t capacity) {
    if (raw.size() > std::numeric_limits<uint32_t>::max() / 2 ||
        capacity > std::numeric_limits<uint32_t>::max()) {
      return 0;
    }
    isal_deflate_stateless_init(&stream);
    stream.level = 1;
    stream.level_buf = level_buffer.data();
    stream.level_buf_size = static_cast<uint32_t>(level_buffer.size());
    stream.gzip_flag = IGZIP_ZLIB;
    stream.flush = NO_FLUSH;
    stream.end_of_stream = 1;
    // igzip does not write through next_in.
    stream.next_in = const_cast<uint8_t*>(reinterpret_cast<const uint8_t*>(raw.data()));
    stream.avail_in = static_cast<uint32_t>(raw.size());
    stream.next_out = reinterpret_cast<uint8_t*>(out);
    stream.avail_out = static_cast<uint32_t>(capacity);
    if (isal_deflate_stateless(&stream) != COMP_OK) return 0;
    return stream.total_out;
  }
};

BlockCompressor::BlockCompressor(VtkCompressor compressor, int level)
    : compressor_(compressor), level_(level) {
  if (compressor_ == VtkCompressor::kZlib) {
    if (level_ == kFastestZlibLevel) {
      isal_ = std::make_unique<IsalCoder>();
    } else {
      deflate_ = libdeflate_alloc_compressor(std::clamp(level_, 1, 12));
    }
  }
}

BlockCompressor::~BlockCompressor() {
  if (deflate_ != nullptr) libdeflate_free_compressor(deflate_);
}

void BlockCompressor::Compress(absl::string_view raw, std::string& out) {
  size_t size = 0;
  switch (compressor_) {
    case VtkCompressor::kZlib: {
      if (isal_ != nullptr) {
        const size_t bound = IsalCoder::Bound(raw.size());
        if (scratch_.size() < bound) scratch_.resize(bound);
        size = isal_->Compress(raw, scratch_.data(), bound);
        if (size > 0) break;
        // Not seen (the bound holds igzip's worst case): libdeflate's fastest level takes over.
        if (deflate_ == nullptr) deflate_ = libdeflate_alloc_compressor(1);
      }
      // Only out of memory leaves no coder; writing the block uncompressed would corrupt the file.
      if (deflate_ == nullptr) throw std::bad_alloc();
      const size_t bound = libdeflate_zlib_compress_bound(deflate_, raw.size());
      if (scratch_.size() < bound) scratch_.resize(bound);
      size = libdeflate_zlib_compress(deflate_, raw.data(), raw.size(), scratch_.data(), bound);
      break;
    }
    case VtkCompressor::kLzma: {
      const size_t bound = lzma_stream_buffer_bound(raw.size());
      if (scratch_.size() < bound) scratch_.resize(bound);
      if (lzma_ == nullptr) lzma_ = std::make_unique<LzmaCoder>();
      size = lzma_->Compress(level_, raw, scratch_);
      break;
    }
    case VtkCompressor::kLz4: {
      const int bound = LZ4_compressBound(static_cast<int>(raw.size()));
      if (scratch_.size() < static_cast<size_t>(bound)) scratch_.resize(bound);
      size = static_cast<size_t>(
          LZ4_compress_default(raw.data(), scratch_.data(), static_cast<int>(raw.size()), bound));
      break;
    }
    case VtkCompressor::kNone:
      out.append(raw.data(), raw.size());
      return;
  }
  out.append(scratch_.data(), size);
}

}  // namespace tetrefine::io
