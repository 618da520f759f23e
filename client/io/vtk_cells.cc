#include "client/io/vtk_cells.h"

#include <cmath>
#include <limits>

#include "absl/strings/str_cat.h"
#include "client/io/io_error.h"

namespace tetrefine::io {

absl::Status CellsToTets(const VtkCells& cells, const VtkCellData& data, size_t num_points,
                         absl::string_view path, MeshFile& file, int64_t& ignored_cells) {
  const size_t n = cells.types.size();
  if (cells.offsets.size() != n + 1 || cells.offsets[0] != 0 ||
      cells.offsets[n] != static_cast<int64_t>(cells.connectivity.size())) {
    return FileError(
        path, absl::StrCat("cell offsets (", cells.offsets.size(), ") do not match ", n,
                           " cells and ", cells.connectivity.size(), " connectivity entries"));
  }
  for (const auto* array : {&data.iteration, &data.quality}) {
    if (!array->empty() && array->size() != n) {
      return FileError(path,
                       absl::StrCat("cell data has ", array->size(), " entries for ", n, " cells"));
    }
  }
  ignored_cells = 0;
  Mesh& mesh = file.mesh;
  mesh.tets.clear();
  file.tet_iteration.clear();
  file.tet_quality.clear();
  for (size_t c = 0; c < n; ++c) {
    const int64_t begin = cells.offsets[c];
    const int64_t end = cells.offsets[c + 1];
    if (begin > end || begin < 0) {
      return FileError(path, absl::StrCat("cell ", c, " has decreasing offsets"));
    }
    if (cells.types[c] != kVtkTetra) {
      ++ignored_cells;
      continue;
    }
    if (end - begin != 4) {
      return FileError(path,
                       absl::StrCat("cell ", c, " is a tetrahedron with ", end - begin, " points"));
    }
    Tet tet;
    for (int k = 0; k < 4; ++k) {
      const int64_t index = cells.connectivity[begin + k];
      if (index < 0 || static_cast<uint64_t>(index) >= num_points) {
        return FileError(path, absl::StrCat("cell ", c, " uses point ", index,
                                            ", out of range for ", num_points, " points"));
      }
      tet[k] = static_cast<uint32_t>(index);
    }
    mesh.tets.push_back(tet);
    if (!data.iteration.empty()) {
      const double it = data.iteration[c];
      if (!(it == std::floor(it) && it >= std::numeric_limits<int32_t>::min() &&
            it <= std::numeric_limits<int32_t>::max())) {
        return FileError(path,
                         absl::StrCat("cell ", c, ": iteration ", it, " is not a 32-bit integer"));
      }
      file.tet_iteration.push_back(static_cast<int32_t>(it));
    }
    if (!data.quality.empty()) {
      const double q = data.quality[c];
      if (!std::isfinite(q) || std::abs(q) > std::numeric_limits<float>::max()) {
        return FileError(path, absl::StrCat("cell ", c, ": quality ", q,
                                            " is not a finite "
                                            "float"));
      }
      file.tet_quality.push_back(static_cast<float>(q));
    }
  }
  return absl::OkStatus();
}

}  // namespace tetrefine::io
