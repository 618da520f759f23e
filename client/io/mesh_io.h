#pragma once

#include <string>
#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "client/io/file_bytes.h"
#include "client/io/mesh_file.h"
#include "client/io/vtu_format.h"

namespace tetrefine::io {

// Reads a tetrahedral mesh, choosing the format from the extension (case-insensitive):
//   .vtu    VTK XML unstructured grid (every encoding and compressor VTK writes)
//   .pvtu   its parallel index: the .vtu pieces it names, merged (ReadPvtu); read only
//   .vtk    legacy VTK, ASCII or BINARY, versions 2 to 5.1
//   .msh    Gmsh 2.2 or 4.1, ASCII or binary
//   .mesh   Medit ASCII          .meshb  Medit binary (libMeshb versions 1 to 4)
//   .ele    TetGen, with the .node file of the same name beside it (tetgen_format.h)
//   .inp    Abaqus input as Gmsh, meshio and CalculiX write it (abaqus_format.h); read only
// Linear tetrahedra are kept; points, lines and surface cells are skipped; any other volume cell
// is an error naming what the file holds. Region labels, their name and the file's frame tag
// come along (MeshFile); points are RAS. The result passed ValidateMeshFile. Errors name the
// file, and the line for text formats; an unknown extension is an error naming the file.
absl::StatusOr<MeshFile> ReadMesh(const std::string& path);

// How WriteMesh encodes each format.
struct MeshWriteOptions {
  VtuWriteOptions vtu{};  // .vtu: ParaView's layout (appended raw, zlib) unless changed
  // .vtk and .msh: binary instead of ASCII. ASCII stays the default for these two: it is what
  // every older reader takes and what people open in an editor; binary is for large meshes.
  bool binary = false;
  int meshb_version = 0;  // .meshb: libMeshb version 1-4, 0 = 3 (see MeshbWriteOptions)
};

// Writes `file` in the format of `path`'s extension (as above; .msh is written as 4.1) after
// checking it with ValidateMeshFile. The bytes go to a temporary file in the same directory
// which is then renamed over `path`, so a failed write never leaves half a file.
// What each format keeps: .vtu/.vtk keep values, iteration, quality, labels (under label_name)
// and the frame tag; .msh keeps values, iteration, quality and labels (as physical groups,
// zero and negative ones too, with region_names as $PhysicalNames); .mesh/.meshb keep only the
// labels (as references); .ele (with its .node; the two are renamed into place together, the
// .node first) keeps only the labels (as the region attribute). Formats without a frame tag get the
// coordinates of `file.frame` untagged: an LPS mesh is written with its LPS numbers, so every input
// vertex keeps its coordinates whatever the format (LpsTagLost says when).
absl::Status WriteMesh(const std::string& path, const MeshFile& file,
                       const MeshWriteOptions& options = {});
// As WriteMesh, but into `staged` (client/io/file_bytes.h): the files are renamed into place
// only by staged.Commit(), with the others staged there.
absl::Status StageMesh(const std::string& path, const MeshFile& file,
                       const MeshWriteOptions& options, StagedFiles& staged);

// The bytes WriteMesh would write for `path` (the format from its extension), without writing
// them: for callers that send or time the encoding on its own. For an .ele, its .node's bytes
// followed by its own.
absl::StatusOr<std::string> FormatMesh(const std::string& path, const MeshFile& file,
                                       const MeshWriteOptions& options = {});

// True when writing `file` to `path` loses its frame tag: an LPS mesh to .msh, .mesh or .meshb,
// whose readers (tetrefine's too) then take the LPS coordinates as RAS. For a warning.
bool LpsTagLost(const std::string& path, const MeshFile& file);

// The distinct negative labels of `file`, ascending, when `path` is a .msh: they are written as
// negative physical groups, which meshio and tetrefine read back as they are, but which Gmsh
// takes as the group of the absolute value with the orientation reversed (a Gmsh save as
// MSH 2.2 merges -L into L and turns those tets inside out). Empty otherwise. For a warning.
std::vector<int32_t> NegativeGmshLabels(const std::string& path, const MeshFile& file);

// True when `path` has one of the mesh extensions above (ReadMesh reads it).
bool IsMeshPath(const std::string& path);
// True when `path` names a surface format (.stl .ply .obj .off .vtp .poly .smesh), which ReadMesh
// refuses saying how to fill it with tets.
bool IsSurfacePath(const std::string& path);
// The error ReadMesh gives for an extension it has no reader for: for a surface format, what to
// do about it; otherwise the list of mesh extensions. Names `path`.
absl::Status UnknownExtension(const std::string& path);
// True when WriteMesh writes `path`: every extension above but .pvtu (written as pieces) and
// .inp (read only).
bool IsWritableMeshPath(const std::string& path);

}  // namespace tetrefine::io
