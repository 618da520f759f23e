// BlockCompressor against two decoders: tetrefine's own (libdeflate, lzma, lz4) and, for zlib,
// zlib's uncompress, the decoder VTK and ParaView use.
#include "client/io/vtk_compressor.h"

#include <gtest/gtest.h>
#include <zlib.h>

#include <cstdint>
#include <random>
#include <string>
#include <vector>

#include "absl/strings/str_cat.h"

namespace tetrefine::io {
namespace {

// Blocks of the kinds a mesh file holds: constant runs (labels, cell types), slowly varying
// integers (offsets, connectivity), doubles (coordinates; barely compressible) and random bytes.
std::string ArrayBlock(int kind, size_t size, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::string out(size, '\0');
  for (size_t i = 0; i < size; ++i) {
    switch (kind) {
      case 0:
        out[i] = 10;
        break;
      case 1: {
        const uint32_t word = static_cast<uint32_t>(4 * (i / 4) + rng() % 3);
        out[i] = static_cast<char>(word >> (8 * (i % 4)));
        break;
      }
      case 2: {
        const double x = std::uniform_real_distribution<double>(-100, 100)(rng);
        out[i] = reinterpret_cast<const char*>(&x)[i % 8];
        break;
      }
      default:
        out[i] = static_cast<char>(rng());
    }
  }
  return out;
}

TEST(IoVtkCompressor, EveryZlibLevelDecodesWithLibdeflateAndZlib) {
  const std::vector<size_t> sizes = {0, 1, 7, 1000, 32768, 65536 + 3, 300000};
  int checked = 0;
  for (int level : {kFastestZlibLevel, 1, 6, 12}) {
    BlockCompressor coder(VtkCompressor::kZlib, level);
    for (int kind = 0; kind < 4; ++kind) {
      for (size_t size : sizes) {
        SCOPED_TRACE(absl::StrCat("level ", level, ", kind ", kind, ", ", size, " bytes"));
        const std::string raw = ArrayBlock(kind, size, 1000 * kind + size);
        std::string compressed = "prefix";  // Compress appends
        coder.Compress(raw, compressed);
        ASSERT_GT(compressed.size(), 6u);
        const std::string block = compressed.substr(6);
        std::string ours(raw.size(), '\0');
        ASSERT_TRUE(DecompressBlock(VtkCompressor::kZlib, block, ours.data(), ours.size()).ok());
        EXPECT_EQ(ours, raw);
        std::string theirs(raw.size() + 1, '\0');
        uLongf produced = theirs.size();
        ASSERT_EQ(uncompress(reinterpret_cast<Bytef*>(theirs.data()), &produced,
                             reinterpret_cast<const Bytef*>(block.data()), block.size()),
                  Z_OK);
        theirs.resize(produced);
        EXPECT_EQ(theirs, raw);
        // Incompressible data grows by headers only (stored blocks), never by a factor.
        EXPECT_LE(block.size(), raw.size() + raw.size() / 64 + 64);
        if (kind == 0 && size >= 1000) {
          EXPECT_LT(block.size(), raw.size() / 20);
        }
        ++checked;
      }
    }
  }
  EXPECT_EQ(checked, 4 * 4 * 7);
}

// A block that decodes to more or fewer bytes than expected is refused, whichever coder made it.
TEST(IoVtkCompressor, WrongDecodedSizeIsRefused) {
  const std::string raw = ArrayBlock(1, 5000, 7);
  for (int level : {kFastestZlibLevel, 1}) {
    BlockCompressor coder(VtkCompressor::kZlib, level);
    std::string block;
    coder.Compress(raw, block);
    std::string out(raw.size() + 1, '\0');
    EXPECT_FALSE(DecompressBlock(VtkCompressor::kZlib, block, out.data(), raw.size() - 1).ok());
    EXPECT_FALSE(DecompressBlock(VtkCompressor::kZlib, block, out.data(), raw.size() + 1).ok());
    EXPECT_TRUE(DecompressBlock(VtkCompressor::kZlib, block, out.data(), raw.size()).ok());
  }
}

// The fastest coder compresses the arrays a refined mesh writes about as well as libdeflate's
// level 1 (bench figures in client/io/vtu_writer.cc): within 25% on each kind.
// A block's bytes must not depend on what its coder compressed before: the writer hands blocks
// to per-thread coders in whatever order the scheduler picks, and a file's bytes must be the same
// from run to run (a sweep found .vtu outputs differing between identical runs while the data
// decoded the same).
TEST(IoVtkCompressor, ABlocksBytesDoNotDependOnTheCodersHistory) {
  const std::vector<std::pair<VtkCompressor, int>> coders = {
      {VtkCompressor::kZlib, kFastestZlibLevel},
      {VtkCompressor::kZlib, 1},
      {VtkCompressor::kZlib, 6},
      {VtkCompressor::kLzma, 1},
      {VtkCompressor::kLz4, 0}};
  for (const auto& [compressor, level] : coders) {
    for (int kind = 0; kind < 4; ++kind) {
      SCOPED_TRACE(absl::StrCat("compressor ", static_cast<int>(compressor), " level ", level,
                                " kind ", kind));
      const std::string raw = ArrayBlock(kind, 32768, 7 + kind);
      std::string fresh;
      BlockCompressor(compressor, level).Compress(raw, fresh);
      BlockCompressor used(compressor, level);
      for (int other = 0; other < 4; ++other) {
        // Blocks that share runs with `raw` (the same generator, other seeds and sizes), so
        // that a stale match table would find candidates in it.
        std::string ignored;
        used.Compress(ArrayBlock(other, 32768 - 24 * other, 7 + kind), ignored);
        used.Compress(ArrayBlock(kind, 20000, 3 + other), ignored);
        std::string again;
        used.Compress(raw, again);
        EXPECT_EQ(again, fresh) << "after " << other;
      }
    }
  }
}

TEST(IoVtkCompressor, FastestZlibKeepsTheRatio) {
  for (int kind = 0; kind < 3; ++kind) {
    const std::string raw = ArrayBlock(kind, 32768, 99 + kind);
    BlockCompressor fastest(VtkCompressor::kZlib, kFastestZlibLevel);
    BlockCompressor libdeflate(VtkCompressor::kZlib, 1);
    std::string a, b;
    fastest.Compress(raw, a);
    libdeflate.Compress(raw, b);
    EXPECT_LE(a.size(), b.size() + b.size() / 4 + 16) << "kind " << kind;
  }
}

}  // namespace
}  // namespace tetrefine::io
