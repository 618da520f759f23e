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
};

// Fills file.mesh.tets from the tetrahedra (type 10) of `cells`, and the per-tet arrays (and
// label_name) from the entries of `data` for those cells. Points, lines and surface cells are
// skipped; other volume cells are an error naming what the file holds (CellCensus). Checks the
// layout, that each tet has 4 indices below `num_points`, that iterations and labels are int32
// and qualities float-finite.
absl::Status CellsToTets(const VtkCells& cells, const VtkCellData& data, size_t num_points,
                         absl::string_view path, MeshFile& file);

}  // namespace tetrefine::io
