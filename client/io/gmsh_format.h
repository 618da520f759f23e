#pragma once

#include <string>

#include "absl/status/statusor.h"
#include "absl/strings/string_view.h"
#include "client/io/mesh_file.h"

namespace tetrefine::io {

// Gmsh .msh, ASCII. Reads format 2.2 and 4.1: keeps tetrahedra (element type 4) and ignores,
// but counts, every other element type (triangles, points, ...). $NodeData "value" (1 component)
// gives the vertex values; $ElementData "iteration" and "quality" the per-tet arrays; other data
// blocks and unknown sections are skipped. Node tags may be sparse. Binary .msh is refused.
// Writes format 4.1: one volume entity holding all nodes and tets, tags 1..V and 1..T, then
// $NodeData "value" and $ElementData "iteration"/"quality" when the MeshFile has them.
struct GmshReadInfo {
  int64_t ignored_elements = 0;  // non-tetrahedral elements skipped
};
absl::StatusOr<MeshFile> ParseGmsh(absl::string_view text, absl::string_view path,
                                   GmshReadInfo* info = nullptr);
std::string FormatGmsh41(const MeshFile& file);

}  // namespace tetrefine::io
