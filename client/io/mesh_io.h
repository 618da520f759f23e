#pragma once

#include <string>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "client/io/mesh_file.h"

namespace tetrefine::io {

// Reads a tetrahedral mesh, choosing the format from the extension (case-insensitive):
//   .vtu   VTK XML unstructured grid     .vtk   legacy VTK, ASCII
//   .msh   Gmsh 2.2 or 4.1, ASCII        .mesh  Medit, ASCII
// Non-tetrahedral cells are ignored. The result passed ValidateMeshFile. Errors name the file,
// and the line for text formats; an unknown extension is an error naming the file.
absl::StatusOr<MeshFile> ReadMesh(const std::string& path);

// Writes `file` in the format of `path`'s extension (as above; .msh is written as 4.1) after
// checking it with ValidateMeshFile. The bytes go to a temporary file in the same directory
// which is then renamed over `path`, so a failed write never leaves half a file.
// What each format keeps: .vtu/.vtk/.msh keep values, iteration and quality; .mesh keeps only
// iteration (as the Medit tet reference).
absl::Status WriteMesh(const std::string& path, const MeshFile& file);

}  // namespace tetrefine::io
