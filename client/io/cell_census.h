#pragma once

#include <cstdint>
#include <map>
#include <string>

#include "absl/status/status.h"
#include "absl/strings/string_view.h"

namespace tetrefine::io {

// What a reader does with a cell of the file that is not a linear tetrahedron.
//   kSkip:        points, lines and surface cells (of any order): dropped, as boundary markers
//                 and surface meshes carry nothing a volume refinement needs.
//   kUnsupported: volume cells that are not linear tetrahedra (hexahedra, wedges, pyramids,
//                 quadratic tetrahedra, ...): refining around them would leave a partial mesh,
//                 so the file is refused with a census of what it holds.
enum class CellFate { kSkip, kUnsupported };

// A kind of cell as the messages name it.
struct CellKind {
  std::string singular;  // "hexahedron"
  std::string plural;    // "hexahedra"
  CellFate fate;
};

// Counts the cells of a file by kind while a reader walks them, then says whether the file can
// be used.
class CellCensus {
 public:
  // `n` tetrahedra, n >= 0. Counts saturate at INT64_MAX (they come from file headers).
  void AddTets(int64_t n);
  // `n` cells of `kind`; kinds are told apart by their plural name. n <= 0 is ignored; counts
  // saturate at INT64_MAX.
  void Add(const CellKind& kind, int64_t n);

  // OK unless an unsupported cell was found, or nothing but skipped cells was. The error names
  // every kind and count, e.g. "<path>: 120 hexahedra and no tetrahedra; tetrefine refines
  // linear tetrahedra only (split the other cells into tetrahedra first)".
  absl::Status Check(absl::string_view path) const;

  int64_t tets() const { return tets_; }
  int64_t skipped() const;
  // The skipped cells' counts by kind (plural name), e.g. {"lines": 1, "triangles": 180}: for
  // MeshFile::skipped_cells.
  std::map<std::string, int64_t> SkippedCells() const;

 private:
  struct Entry {
    CellKind kind;
    int64_t count = 0;
  };
  int64_t tets_ = 0;
  std::map<std::string, Entry> kinds_;  // by plural name, so messages list kinds alphabetically
};

// VTK cell type code (vtkCellType.h) to kind; type 10 (VTK_TETRA) is the tetrahedron and must not
// be passed. Unknown codes count as unsupported "cells of VTK type N".
CellKind VtkCellKind(int64_t vtk_type);

}  // namespace tetrefine::io
