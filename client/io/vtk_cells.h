#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "absl/status/status.h"
#include "absl/strings/string_view.h"
#include "client/io/mesh_file.h"

namespace tetrefine::io {

// VTK's cell type code for a linear tetrahedron.
inline constexpr int kVtkTetra = 10;

// A VTK cell list in the offsets/connectivity layout (legacy 5.x and XML); legacy 2.x-4.x files
// are converted to it. Cell c uses connectivity[offsets[c] .. offsets[c + 1]).
struct VtkCells {
  std::vector<int64_t> offsets;  // cells + 1 entries, offsets[0] = 0
  std::vector<int64_t> connectivity;
  std::vector<int64_t> types;  // one VTK cell type per cell
};

// Per-cell arrays as read, one entry per cell of any type (or empty when absent).
struct VtkCellData {
  std::vector<double> iteration;
  std::vector<double> quality;
  std::vector<int64_t> label;
  std::string label_name;  // the array `label` came from
  int label_rank = -1;     // its LabelNameRank, to keep the most preferred of several
  // Per cell, whether it is a ghost: a copy of a cell another piece owns (GhostCellFlags).
  std::vector<uint8_t> ghost;
};

// Whether `name` is a cell array that marks ghost cells: "vtkGhostType" (VTK 7 and later) or
// "vtkGhostLevels" (before).
bool IsGhostArrayName(absl::string_view name);

// The ghost flags of the cell array `name` (IsGhostArrayName) holding `values`, into
// data->ghost: a cell is a ghost when vtkGhostType has its DUPLICATECELL bit (1) set, or
// vtkGhostLevels is above 0. Those are the cells vtkUnstructuredGrid::RemoveGhostCells (and so
// ParaView's "Remove Ghost Information") drops; VTK's parallel writers add them around each piece
// when asked for ghost levels (vtkXMLPUnstructuredGridWriter::SetGhostLevel, a .pvtu's
// GhostLevel="1"). Other bits (HIDDENCELL, REFINEDCELL, ...) leave a cell in. Errors name
// `path`: a value outside [0, 255].
absl::Status GhostCellFlags(absl::string_view name, const std::vector<int64_t>& values,
                            absl::string_view path, VtkCellData* data);

// Fills file.mesh.tets from the tetrahedra (type 10) of `cells`, and the per-tet arrays (and
// label_name) from the entries of `data` for those cells. Points, lines and surface cells are
// skipped; other volume cells are an error naming what the file holds (CellCensus). Ghost cells
// (data.ghost) are skipped whatever their type, counted in file.ghost_cells_skipped, and the
// points no kept tet uses are dropped with their values (file.mesh.points and mesh.values, set
// before the call), as VTK's RemoveGhostCells does: a piece written with ghost levels lists its
// neighbours' boundary tets too, which would otherwise be read as duplicates or overlaps. Checks
// the layout, that each tet has 4 indices below `num_points`, that iterations and labels are
// int32 and qualities float-finite.
absl::Status CellsToTets(const VtkCells& cells, const VtkCellData& data, size_t num_points,
                         absl::string_view path, MeshFile& file);

}  // namespace tetrefine::io
