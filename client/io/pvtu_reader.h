#pragma once

#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "absl/strings/string_view.h"
#include "client/io/mesh_file.h"

namespace tetrefine::io {

// The piece files a .pvtu index names (<PUnstructuredGrid><Piece Source="..."/>), in order, each
// resolved against the directory of `path` unless absolute. Errors name `path`: not a
// PUnstructuredGrid, no pieces, a piece without a Source.
absl::StatusOr<std::vector<std::string>> ParsePvtuIndex(absl::string_view text,
                                                        absl::string_view path);

// One mesh from the pieces of a parallel unstructured grid (`paths[k]` names pieces[k] in
// messages). A vertex on the boundary between pieces is in each (what VTK's parallel writers and
// a sharded `refine --pvtu` write): a point of a piece whose coordinates equal, bit for bit, a
// point of an earlier piece is that point; points repeated within one piece stay apart. Tets and
// their arrays follow in piece order. The pieces must hold the same arrays (values, iteration,
// quality, labels under one name) and the same frame tag, and a shared vertex the same value in
// each: otherwise an INVALID_ARGUMENT names the piece (and the vertex).
absl::StatusOr<MeshFile> MergePvtuPieces(std::vector<MeshFile> pieces,
                                         const std::vector<std::string>& paths);

// Reads the .pvtu at `path` and every piece it names (as .vtu), and merges them
// (MergePvtuPieces). Errors name the index or the piece.
absl::StatusOr<MeshFile> ReadPvtu(const std::string& path);

}  // namespace tetrefine::io
