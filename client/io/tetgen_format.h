#pragma once

#include <string>

#include "absl/status/statusor.h"
#include "absl/strings/string_view.h"
#include "client/io/mesh_file.h"

namespace tetrefine::io {

// TetGen's own mesh files, what `tetgen` writes by default: a .node file (points) and an .ele
// file (tets) of the same name. Both are text with '#' comments:
//   .node: "<points> 3 <attributes> <boundary markers 0|1>", then per point
//          "<index> <x> <y> <z> [attributes...] [marker]"
//   .ele:  "<tets> <nodes per tet 4|10> <region attributes>", then per tet
//          "<index> <n1> <n2> <n3> <n4> [attributes...]"
// Indices run consecutively from 0 or 1 (TetGen numbers its output from its input's base); each
// file's first index sets its base. Reading keeps the tets as TetGen orders their corners and the
// first region attribute as the region label (label_name "tetgen:ref", meshio's name), which must
// be whole numbers in int32's range; point attributes and boundary markers are dropped (named in
// dropped_arrays). Ten nodes per tet (tetgen -o2) is an error naming quadratic tets.
// Errors name the file and line.
absl::StatusOr<MeshFile> ParseTetgen(absl::string_view node_text, absl::string_view ele_text,
                                     absl::string_view node_path, absl::string_view ele_path);

// The .node file beside an .ele file: "dir/ball.1.ele" -> "dir/ball.1.node", and in capitals
// beside an .ELE: "BALL.1.ELE" -> "BALL.1.NODE" (the extension's case is the .ele's).
std::string TetgenNodePath(const std::string& ele_path);

// The two files for `file`, numbered from 1, coordinates to the bit (shortest round trip): the
// .node, and the .ele with the labels as the region attribute (when it has labels). TetGen's files
// have no names for attributes, so the vertex values, iteration and quality are not written (as in
// Medit files); `tetgen -r` reads the pair back.
struct TetgenFiles {
  std::string node;
  std::string ele;
};
TetgenFiles FormatTetgen(const MeshFile& file);

}  // namespace tetrefine::io
