#pragma once

// `tetrefine refine --pvtu`: the result as pieces of a VTK parallel dataset.

#include <vector>

#include "client/io/mesh_file.h"

namespace tetrefine::cli {

// Cuts `file` into `pieces` spatially compact pieces the way sharding cuts a mesh into parts
// (sharding::PartitionTets: recursive bisection of tet centroids, a pure function of the mesh),
// each with its own vertex numbering: a vertex on the boundary between pieces is in each of
// them, as VTK expects of pieces. Every per-vertex and per-tet array, the label name and the
// frame go with the piece. `pieces` is clamped to [1, tets]; every piece has at least one tet.
// Requires a file that passes ValidateMeshFile with at least one tet.
std::vector<io::MeshFile> CutIntoPieces(const io::MeshFile& file, int pieces);

}  // namespace tetrefine::cli
