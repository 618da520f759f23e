#pragma once

#include <string>
#include <vector>

#include "absl/status/status.h"
#include "client/io/mesh_file.h"
#include "client/io/vtu_format.h"

namespace tetrefine::io {

// The .pvtu index of a VTK XML parallel unstructured grid, laid out as VTK's
// vtkXMLPUnstructuredGridWriter writes it: the arrays every piece holds, with the names and types
// FormatVtu gives them (PPointData "value", PCellData "iteration", "quality" and the labels,
// PPoints Float64), then one <Piece Source="..."/> per file of `sources`, in order. `like` is one
// of the pieces (any MeshFile with the same arrays): it says which arrays are declared.
// ParaView and VTK resolve each Source against the .pvtu's directory.
std::string FormatPvtu(const MeshFile& like, const std::vector<std::string>& sources);

// The path of piece `k` of the .pvtu at `path`: "dir/out.pvtu" -> "dir/out_<k>.vtu", beside the
// index, as VTK names them.
std::string PvtuPiecePath(const std::string& path, int k);

// Writes each of `pieces` as a .vtu (FormatVtu with `options`) at PvtuPiecePath(path, k), then
// the index at `path`; all of them to temporaries first, renamed into place together, the
// index last (StagedFiles), so a failure leaves the files of a run before as they were, never an
// index naming missing pieces or another run's. Pieces share no vertex numbering: a
// vertex on the boundary of two pieces is in both (what VTK expects of pieces).
// Errors: INVALID_ARGUMENT when there are no pieces, when a piece fails ValidateMeshFile (the
// message names its file) or when the pieces do not hold the same arrays (named, with the
// piece's index); the file system's errors name the file.
absl::Status WritePvtu(const std::string& path, const std::vector<MeshFile>& pieces,
                       const VtuWriteOptions& options = {});

}  // namespace tetrefine::io
