#pragma once

#include <string>

#include "absl/status/statusor.h"
#include "absl/strings/string_view.h"
#include "client/io/mesh_file.h"

namespace tetrefine::io {

// Medit (Gamma Mesh Format) as MMG, TetGen and libMeshb write it: ASCII .mesh and binary .meshb.
// Every element has an integer reference; a tet's reference is its region label (mesh.labels,
// label_name "medit:ref"), so a read always fills mesh.labels and a write of a MeshFile without
// labels writes 0. Vertex references are read and dropped (written as 0). Vertex values,
// iteration and quality have no place in these files (a .sol companion is not written): they are
// dropped on write and empty on read. Points, edges and surface elements are skipped; other
// volume elements (Hexahedra, Prisms, Pyramids, TetrahedraP2, ...) are an error naming what the
// file holds. Only Dimension 3 is read.

// ASCII .mesh (MeshVersionFormatted 1 to 4, keywords case-insensitive, '#' comments).
absl::StatusOr<MeshFile> ParseMedit(absl::string_view text, absl::string_view path);
std::string FormatMedit(const MeshFile& file);

// Binary .meshb, versions as libMeshb defines them (int32 keyword codes; either byte order,
// told by the leading code word 1):
//   1: float32 reals, int32 integers, int32 positions
//   2: float64 reals, int32 integers, int32 positions
//   3: float64 reals, int32 integers, int64 positions
//   4: float64 reals, int64 integers, int64 positions
// Keywords other than Dimension, Vertices, Tetrahedra and End are skipped through their
// next-keyword position.
struct MeshbReadInfo {
  int version = 0;  // the file's version, so a caller can write the same one back
};
absl::StatusOr<MeshFile> ParseMeshb(absl::string_view bytes, absl::string_view path,
                                    MeshbReadInfo* info = nullptr);

struct MeshbWriteOptions {
  // 1 to 4 as above; 0 chooses 3 (what meshio writes: doubles, 64-bit positions so files may
  // pass 2 GiB), or 4 when vertex numbers pass the int32 range. Version 1 stores float32
  // coordinates: the only one that does not keep doubles exactly. Versions 1 and 2 hold files
  // below 2 GiB only.
  int version = 0;
};
std::string FormatMeshb(const MeshFile& file, const MeshbWriteOptions& options = {});

}  // namespace tetrefine::io
