#include "client/io/vtk_cells.h"

#include <cmath>
#include <limits>

#include "absl/container/flat_hash_map.h"
#include "absl/strings/str_cat.h"
#include "client/io/cell_census.h"
#include "client/io/io_error.h"
#include "core/huge_pages.h"

namespace tetrefine::io {
namespace {

bool IsInt32(int64_t x) {
  return x >= std::numeric_limits<int32_t>::min() && x <= std::numeric_limits<int32_t>::max();
}

// Drops the points no tet uses, and their values, renumbering the tets (after ghost cells went).
void DropUnusedPoints(MeshFile& file) {
  Mesh& mesh = file.mesh;
  // Values of another length are refused later (ValidateMeshFile), with their own message.
  const bool values = mesh.values.size() == mesh.points.size();
  std::vector<int64_t> renamed(mesh.points.size(), -1);
  for (const Tet& t : mesh.tets) {
    for (uint32_t v : t) renamed[v] = 0;
  }
  size_t kept = 0;
  for (size_t v = 0; v < renamed.size(); ++v) {
    if (renamed[v] < 0) continue;
    renamed[v] = static_cast<int64_t>(kept);
    mesh.points[kept] = mesh.points[v];
    if (values) mesh.values[kept] = mesh.values[v];
    ++kept;
  }
  mesh.points.resize(kept);
  if (values) mesh.values.resize(kept);
  for (Tet& t : mesh.tets) {
    for (uint32_t& v : t) v = static_cast<uint32_t>(renamed[v]);
  }
}

}  // namespace

bool IsGhostArrayName(absl::string_view name) {
  return name == "vtkGhostType" || name == "vtkGhostLevels";
}

absl::Status GhostCellFlags(absl::string_view name, const std::vector<int64_t>& values,
                            absl::string_view path, VtkCellData* data) {
  // vtkDataSetAttributes::DUPLICATECELL.
  constexpr int64_t kDuplicateCell = 1;
  data->ghost.resize(values.size());
  for (size_t c = 0; c < values.size(); ++c) {
    const int64_t g = values[c];
    if (g < 0 || g > 255) {
      return FileError(path, absl::StrCat("cell ", c, ": ", name, " ", g,
                                          " is not an unsigned 8-bit ghost flag"));
    }
    data->ghost[c] = name == "vtkGhostLevels" ? g > 0 : (g & kDuplicateCell) != 0;
  }
  return absl::OkStatus();
}

absl::Status CellsToTets(const VtkCells& cells, const VtkCellData& data, size_t num_points,
                         absl::string_view path, MeshFile& file) {
  const size_t n = cells.types.size();
  if (cells.offsets.size() != n + 1 || cells.offsets[0] != 0 ||
      cells.offsets[n] != static_cast<int64_t>(cells.connectivity.size())) {
    return FileError(
        path, absl::StrCat("cell offsets (", cells.offsets.size(), ") do not match ", n,
                           " cells and ", cells.connectivity.size(), " connectivity entries"));
  }
  if (!data.iteration.empty() && data.iteration.size() != n) {
    return FileError(path, absl::StrCat("cell data \"iteration\" has ", data.iteration.size(),
                                        " entries for ", n, " cells"));
  }
  if (!data.quality.empty() && data.quality.size() != n) {
    return FileError(path, absl::StrCat("cell data \"quality\" has ", data.quality.size(),
                                        " entries for ", n, " cells"));
  }
  if (!data.ghost.empty() && data.ghost.size() != n) {
    return FileError(path, absl::StrCat("cell data ghost flags have ", data.ghost.size(),
                                        " entries for ", n, " cells"));
  }
  const auto ghost = [&data](size_t c) { return !data.ghost.empty() && data.ghost[c] != 0; };
  file.ghost_cells_skipped = 0;
  if (!data.label.empty() && data.label.size() != n) {
    return FileError(path, absl::StrCat("cell data \"", data.label_name, "\" has ",
                                        data.label.size(), " entries for ", n, " cells"));
  }
  // Non-tet cells are counted by type here and named once at the end.
  absl::flat_hash_map<int64_t, int64_t> other_types;
  int64_t tets = 0;
  for (size_t c = 0; c < n; ++c) {
    const int64_t begin = cells.offsets[c];
    const int64_t end = cells.offsets[c + 1];
    if (begin > end || begin < 0) {
      return FileError(path, absl::StrCat("cell ", c, " has decreasing offsets"));
    }
    if (ghost(c)) {
      ++file.ghost_cells_skipped;
      continue;
    }
    if (cells.types[c] != kVtkTetra) {
      ++other_types[cells.types[c]];
      continue;
    }
    if (end - begin != 4) {
      return FileError(path,
                       absl::StrCat("cell ", c, " is a tetrahedron with ", end - begin, " points"));
    }
    ++tets;
  }
  CellCensus census;
  census.AddTets(tets);
  for (const auto& [type, count] : other_types) census.Add(VtkCellKind(type), count);
  if (absl::Status s = census.Check(path); !s.ok()) return s;
  file.skipped_cells = census.SkippedCells();

  Mesh& mesh = file.mesh;
  mesh.tets.clear();
  ReserveHuge(mesh.tets, tets);
  file.tet_iteration.clear();
  file.tet_quality.clear();
  file.mesh.labels.clear();
  file.label_name.clear();
  for (size_t c = 0; c < n; ++c) {
    if (cells.types[c] != kVtkTetra || ghost(c)) continue;
    const int64_t begin = cells.offsets[c];
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
      // A quality that is not a finite float makes the array unusable, not the mesh: it is
      // kept as NaN here and DropNonFiniteDerivedArrays drops the array.
      const double q = data.quality[c];
      file.tet_quality.push_back(std::isfinite(q) &&
                                         std::abs(q) <= std::numeric_limits<float>::max()
                                     ? static_cast<float>(q)
                                     : std::numeric_limits<float>::quiet_NaN());
    }
    if (!data.label.empty()) {
      if (!IsInt32(data.label[c])) {
        return FileError(path, absl::StrCat("cell ", c, ": ", data.label_name, " ", data.label[c],
                                            " is not a 32-bit integer"));
      }
      file.mesh.labels.push_back(static_cast<int32_t>(data.label[c]));
    }
  }
  if (!data.label.empty()) file.label_name = data.label_name;
  if (file.ghost_cells_skipped > 0) DropUnusedPoints(file);
  return absl::OkStatus();
}

}  // namespace tetrefine::io
