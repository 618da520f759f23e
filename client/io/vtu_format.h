#pragma once

#include <cstddef>
#include <string>

#include "absl/status/statusor.h"
#include "absl/strings/string_view.h"
#include "client/io/mesh_file.h"
#include "client/io/vtk_compressor.h"

namespace tetrefine::io {

// VTK XML unstructured grid (.vtu): written as one Piece; read with any number of Pieces, which
// are merged as a .pvtu's pieces are (MergePvtuPieces: a point repeated in a later piece, bit
// for bit, is the earlier one).
//
// Reading (pugixml): DataArrays in every form VTK 9 and ParaView write: inline "ascii", inline
// "binary" (base64) and "appended" (raw or base64 <AppendedData>), uncompressed or compressed by
// zlib, lzma or lz4, UInt32 or UInt64 headers, either byte order; <InformationKey> children of a
// DataArray are ignored. Keeps linear tetrahedra (type 10); points, lines and surface cells are
// skipped; other volume cells (hexahedra, wedges, pyramids, quadratic tets, ...) are an error
// naming what the file holds. Point data "value", cell data "iteration" and "quality", and the
// region labels (the cell array LabelNameRank prefers: "gmsh:physical", "medit:ref",
// "CellEntityIds", "region", ...) are read when present. A field-data string array "SPACE" (3D
// Slicer's frame tag) holding LPS or RAS sets MeshFile::frame; LPS points are converted to RAS.
absl::StatusOr<MeshFile> ParseVtu(absl::string_view text, absl::string_view path);

// How FormatVtu stores the arrays. The default is what ParaView's "Save Data" writes: appended
// raw binary, zlib-compressed in 32 KiB blocks, UInt64 headers.
struct VtuWriteOptions {
  enum class Layout {
    kAppendedRaw,   // one <AppendedData encoding="raw"> section (ParaView's default)
    kInlineBase64,  // format="binary" in each DataArray
    kAscii,         // format="ascii" (the compressor is not used)
  };
  Layout layout = Layout::kAppendedRaw;
  VtkCompressor compressor = VtkCompressor::kZlib;
  // The compressor's level: zlib kFastestZlibLevel (0, ISA-L) or 1 (fastest) to 12 (smallest)
  // as libdeflate counts, lzma 0 to 9. The defaults were chosen by measurement on refined meshes
  // (see kDefaultZlibLevel in vtu_writer.cc).
  int level = -1;             // -1: the default
  size_t block_size = 32768;  // VTK's default block size
};

// Writes `file` (which must pass ValidateMeshFile): Points Float64, connectivity and offsets
// Int32 when they fit (Int64 otherwise), types UInt8, point data "value" Float64, cell data
// "iteration" Int32, "quality" Float32 and the labels Int32 named LabelArrayName(file), each only
// when present; little-endian, UInt64 headers, file version 1.0. A tagged frame is written as
// Slicer writes it (field data "SPACE"), with the points in that frame.
std::string FormatVtu(const MeshFile& file, const VtuWriteOptions& options = {});

}  // namespace tetrefine::io
