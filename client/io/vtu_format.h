#pragma once

#include <string>

#include "absl/status/statusor.h"
#include "absl/strings/string_view.h"
#include "client/io/mesh_file.h"

namespace tetrefine::io {

// VTK XML unstructured grid (.vtu), one Piece.
// Reads DataArrays in "ascii" or inline "binary" format (base64, UInt32 or UInt64 headers,
// optionally zlib-compressed as vtkZLibDataCompressor writes), either byte order; appended data
// is not read. Keeps tetrahedra (cell type 10) and ignores other cells; point data "value" and
// cell data "iteration"/"quality" are read when present.
// Writes inline base64 binary, uncompressed, UInt64 headers (file version 1.0): Points Float64,
// connectivity/offsets Int64, types UInt8, point data "value" Float64, cell data "iteration"
// Int32 and "quality" Float32, each present only when the MeshFile has it.
absl::StatusOr<MeshFile> ParseVtu(absl::string_view text, absl::string_view path);
std::string FormatVtu(const MeshFile& file);

}  // namespace tetrefine::io
