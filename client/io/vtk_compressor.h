#pragma once

#include <cstddef>
#include <memory>
#include <optional>
#include <string>

#include "absl/status/status.h"
#include "absl/strings/string_view.h"

struct libdeflate_compressor;  // libdeflate.h

namespace tetrefine::io {

// The block compressors of VTK XML files (the VTKFile "compressor" attribute). VTK compresses
// each block of an array (32 KiB by default) on its own, so blocks can be coded in parallel.
//   kZlib: vtkZLibDataCompressor, a zlib stream per block.
//   kLzma: vtkLZMADataCompressor, an .xz stream per block (liblzma).
//   kLz4:  vtkLZ4DataCompressor, a raw LZ4 block per block (liblz4).
enum class VtkCompressor { kNone, kZlib, kLzma, kLz4 };

// The attribute value ("vtkZLibDataCompressor", ...) to compressor; nullopt when unknown.
std::optional<VtkCompressor> VtkCompressorFromName(absl::string_view name);
// The attribute value; "" for kNone.
absl::string_view VtkCompressorName(VtkCompressor compressor);

// How many times larger than its compressed size a block can decode to, with margin: zlib's
// deflate cannot exceed 1032:1 and LZ4's about 255:1; xz reaches about 7000:1 on constant data.
// A header claiming more is corrupt, which lets readers refuse it before allocating.
size_t MaxExpansion(VtkCompressor compressor);

// Decodes one block into out[0 .. decoded_size), failing unless it decodes to exactly that many
// bytes. The error carries no path; callers add it.
absl::Status DecompressBlock(VtkCompressor compressor, absl::string_view compressed, char* out,
                             size_t decoded_size);

// zlib's level for BlockCompressor that asks for ISA-L's igzip (level 1), the fastest coder, whose
// bytes vary from run to run (below).
inline constexpr int kFastestZlibLevel = 0;

// Compresses blocks one after another, reusing its coder state: one per thread.
// `level` is the compressor's own scale: zlib kFastestZlibLevel (ISA-L) or 1-12 as libdeflate
// counts, lzma 0-9; LZ4 ignores it. Every zlib coder writes the format VTK reads: libdeflate is
// about 2.3x faster than zlib's own deflate at level 1 on refined meshes for 6% more bytes, and
// ISA-L 1.9x faster than libdeflate's level 1 for 2% more (bench/mesh_io_bench; vtu_writer.cc).
// ISA-L's bytes are not reproducible: the same block, given to a fresh coder, came out 1-3 bytes
// longer or shorter in about 1 of 3000 blocks of a `tetrefine refine` run, even with one thread
// (2026-11-27; its levels 1 and 2, not 0); what they decode to never changes. libdeflate's bytes
// depend only on the block and the level, which is why vtu_writer.cc's default is libdeflate's.
class BlockCompressor {
 public:
  BlockCompressor(VtkCompressor compressor, int level);
  ~BlockCompressor();
  BlockCompressor(const BlockCompressor&) = delete;
  BlockCompressor& operator=(const BlockCompressor&) = delete;

  // Appends the compressed form of `raw` to `out`.
  void Compress(absl::string_view raw, std::string& out);

 private:
  VtkCompressor compressor_;
  int level_;
  ::libdeflate_compressor* deflate_ = nullptr;
  struct IsalCoder;  // ISA-L's stream and level buffer, kept between blocks
  std::unique_ptr<IsalCoder> isal_;
  struct LzmaCoder;  // an lzma_stream kept between blocks
  std::unique_ptr<LzmaCoder> lzma_;
  // Where a block is compressed before its compressed bytes are appended to `out`: sized to the
  // coder's worst case once and reused. Resizing `out` to that bound for every block zeroed the
  // bound and faulted in fresh pages for it, a quarter of the page faults of a whole
  // `tetrefine refine` writing a 3.3 M-tet .vtu (bench/file_to_file.sh, 2026-11-24).
  std::string scratch_;
};

}  // namespace tetrefine::io
