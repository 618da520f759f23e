#pragma once

#include <cstddef>
#include <optional>
#include <string>

#include "absl/status/status.h"
#include "absl/strings/string_view.h"

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

// Appends the compressed form of `raw` to `out`. `level` is the compressor's own scale (zlib and
// lzma 1-9; LZ4 ignores it).
void CompressBlock(VtkCompressor compressor, int level, absl::string_view raw, std::string& out);

}  // namespace tetrefine::io
