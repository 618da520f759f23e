#pragma once

#include <string>

#include "absl/status/statusor.h"
#include "absl/strings/string_view.h"
#include "client/io/mesh_file.h"

namespace tetrefine::io {

// Medit ASCII .mesh (MeshVersionFormatted 1 or 2, Dimension 3). Reads Vertices and Tetrahedra;
// other sections (Triangles, Edges, Corners, Normals, ...) are skipped. Medit gives every
// element an integer reference: a tet's reference carries MeshFile::tet_iteration (so a read
// always fills tet_iteration; a write of a MeshFile without it writes 0). Vertex values and tet
// quality have no place in a .mesh (a .sol companion is not written), so they are dropped on
// write and empty on read.
absl::StatusOr<MeshFile> ParseMedit(absl::string_view text, absl::string_view path);
std::string FormatMedit(const MeshFile& file);

}  // namespace tetrefine::io
