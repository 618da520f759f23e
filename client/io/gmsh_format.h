#pragma once

#include <cstdint>
#include <string>

#include "absl/status/statusor.h"
#include "absl/strings/string_view.h"
#include "client/io/mesh_file.h"

namespace tetrefine::io {

// Gmsh .msh, formats 2.2 and 4.1, ASCII or binary (`gmsh -bin`; either byte order, detected from
// the file's endianness word).
//
// Reading keeps linear tetrahedra (element type 4). Points, lines and surface elements are
// skipped (boundary markers); other volume elements (hexahedra, prisms, pyramids, second-order
// tetrahedra, ...) are an error naming what the file holds. Region labels are the physical
// groups: in 2.2 the first element tag, in 4.1 the first physical tag of the element's entity
// ($Entities); a tet without a physical group gets label 0, and a file without any physical
// group gives no labels. label_name is then "gmsh:physical" (meshio's name for them).
// $NodeData "value" (1 component) gives the vertex values, $ElementData "iteration" and
// "quality" the per-tet arrays; other sections are skipped. Node and element tags may be sparse
// and unordered; vertices are returned in node-tag order and tets in element-tag order (what
// meshio and Gmsh's API return), whatever order the blocks had.
// Gmsh's element type number of a linear tetrahedron.
inline constexpr int kGmshTet = 4;

struct GmshReadInfo {
  int64_t ignored_elements = 0;  // point, line and surface elements skipped
};
absl::StatusOr<MeshFile> ParseGmsh(absl::string_view text, absl::string_view path,
                                   GmshReadInfo* info = nullptr);

struct GmshWriteOptions {
  bool binary = false;  // "4.1 1 8" binary (native little-endian) instead of ASCII
};

// Writes format 4.1: one volume entity per distinct label (physical group = the label, zero and
// negative ones too: see the writer for why), or a single volume entity without labels; all nodes
// in the first volume entity, tags 1..V; tets grouped by label in ascending label order (within a
// label, in tet order), element tags 1..T in that order, so a labelled mesh reads back in that
// order; then $NodeData "value" and $ElementData "iteration"/"quality" in element order, as
// meshio needs, when the MeshFile has them.
std::string FormatGmsh41(const MeshFile& file, const GmshWriteOptions& options = {});

// Puts the tets of a labelled `file` (with their labels, iterations and qualities) in the order
// FormatGmsh41 writes them and ParseGmsh reads them back: by ascending label, each label's tets
// in their order. An unlabelled file is left as it is.
void OrderTetsAsGmshWrites(MeshFile& file);

}  // namespace tetrefine::io
