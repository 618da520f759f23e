#pragma once

#include "absl/strings/string_view.h"

namespace tetrefine::io {

// Which per-cell integer array of a VTK file (.vtu, .vtk) holds region labels. Files name them
// after the tool that made them, so a reader recognises these names, case-insensitively, in this
// order of preference:
//   "gmsh:physical"  meshio's name for Gmsh physical groups (gmsh:geometrical is the entity)
//   "medit:ref"      meshio's name for Medit references
//   "tetgen:ref"     meshio's name for TetGen region attributes
//   "CellEntityIds"  VMTK and VTK's mesh generators
//   "region", "regions", "labels", "label", "MaterialIds", "material", "materials", "subdomain"
// The preference matters only when a file holds several of them (meshio writes gmsh:physical
// beside gmsh:geometrical, which is not in the list).
// Returns the rank of `name` in that list (0 = most preferred), or -1 when it is not a label name.
int LabelNameRank(absl::string_view name);

}  // namespace tetrefine::io
