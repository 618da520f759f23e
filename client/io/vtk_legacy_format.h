#pragma once

#include <string>

#include "absl/status/statusor.h"
#include "absl/strings/string_view.h"
#include "client/io/mesh_file.h"

namespace tetrefine::io {

// Legacy VTK .vtk, ASCII, DATASET UNSTRUCTURED_GRID. Reads file versions 2.x-4.x (CELLS with a
// count per cell) and 5.x (OFFSETS/CONNECTIVITY); keeps tetrahedra (cell type 10) and ignores
// other cells. Point data "value" and cell data "iteration"/"quality" are read from SCALARS or
// FIELD arrays; other attributes are skipped. Writes version 3.0 (readable by every VTK and
// ParaView): POINTS double, CELLS/CELL_TYPES 10, POINT_DATA SCALARS value double, CELL_DATA
// SCALARS iteration int and quality float, each present only when the MeshFile has it.
absl::StatusOr<MeshFile> ParseVtkLegacy(absl::string_view text, absl::string_view path);
std::string FormatVtkLegacy(const MeshFile& file);

}  // namespace tetrefine::io
