#include "client/io/cell_census.h"

#include <cstdint>
#include <vector>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_join.h"
#include "client/io/io_error.h"

namespace tetrefine::io {
namespace {

// Counts come from the file's own headers (a .meshb keyword may declare any int64 count), so a
// sum of them must not overflow: it saturates at the largest int64, which only a hostile or
// corrupt file reaches and which the message then shows as is. (The meshb fuzzer found the
// overflow: two keywords declaring counts near 2^63.)
int64_t SaturatingAdd(int64_t a, int64_t b) {
  int64_t sum = 0;
  if (__builtin_add_overflow(a, b, &sum)) return b > 0 ? INT64_MAX : INT64_MIN;
  return sum;
}

std::string Counted(int64_t n, const CellKind& kind) {
  return absl::StrCat(n, " ", n == 1 ? kind.singular : kind.plural);
}

}  // namespace

void CellCensus::AddTets(int64_t n) { tets_ = SaturatingAdd(tets_, n); }

void CellCensus::Add(const CellKind& kind, int64_t n) {
  if (n <= 0) return;
  Entry& entry = kinds_[kind.plural];
  entry.kind = kind;
  entry.count = SaturatingAdd(entry.count, n);
}

int64_t CellCensus::skipped() const {
  int64_t n = 0;
  for (const auto& [name, entry] : kinds_) {
    if (entry.kind.fate == CellFate::kSkip) n = SaturatingAdd(n, entry.count);
  }
  return n;
}

std::map<std::string, int64_t> CellCensus::SkippedCells() const {
  std::map<std::string, int64_t> out;
  for (const auto& [name, entry] : kinds_) {
    if (entry.kind.fate == CellFate::kSkip) out[name] = entry.count;
  }
  return out;
}

absl::Status CellCensus::Check(absl::string_view path) const {
  std::vector<std::string> unsupported;
  std::vector<std::string> skipped;
  for (const auto& [name, entry] : kinds_) {
    (entry.kind.fate == CellFate::kUnsupported ? unsupported : skipped)
        .push_back(Counted(entry.count, entry.kind));
  }
  const std::string tets =
      tets_ == 0 ? "no tetrahedra"
                 : Counted(tets_, CellKind{"tetrahedron", "tetrahedra", CellFate::kSkip});
  if (!unsupported.empty()) {
    return FileError(path, absl::StrCat(absl::StrJoin(unsupported, ", "),
                                        tets_ == 0 ? " and " : " beside ", tets,
                                        "; tetrefine refines linear tetrahedra only (split the "
                                        "other cells into linear tetrahedra first)"));
  }
  if (tets_ == 0 && !skipped.empty()) {
    return FileError(path, absl::StrCat(absl::StrJoin(skipped, ", "),
                                        " and no tetrahedra: a surface or line mesh, not a "
                                        "volume mesh (tetrefine refines linear tetrahedra)"));
  }
  return absl::OkStatus();
}

CellKind VtkCellKind(int64_t vtk_type) {
  const auto skip = [](const char* singular, const char* plural) {
    return CellKind{singular, plural, CellFate::kSkip};
  };
  const auto volume = [](const char* singular, const char* plural) {
    return CellKind{singular, plural, CellFate::kUnsupported};
  };
  switch (vtk_type) {
    case 0:
      return skip("empty cell", "empty cells");
    case 1:
      return skip("vertex", "vertices");
    case 2:
      return skip("poly-vertex", "poly-vertices");
    case 3:
      return skip("line", "lines");
    case 4:
      return skip("polyline", "polylines");
    case 5:
      return skip("triangle", "triangles");
    case 6:
      return skip("triangle strip", "triangle strips");
    case 7:
      return skip("polygon", "polygons");
    case 8:
      return skip("pixel", "pixels");
    case 9:
      return skip("quad", "quads");
    case 11:
      return volume("voxel", "voxels");
    case 12:
      return volume("hexahedron", "hexahedra");
    case 13:
      return volume("wedge", "wedges");
    case 14:
      return volume("pyramid", "pyramids");
    case 15:
      return volume("pentagonal prism", "pentagonal prisms");
    case 16:
      return volume("hexagonal prism", "hexagonal prisms");
    case 21:
      return skip("quadratic line", "quadratic lines");
    case 35:
      return skip("cubic line", "cubic lines");
    case 22:
    case 34:
      return skip("quadratic triangle", "quadratic triangles");
    case 23:
    case 28:
    case 30:
      return skip("quadratic quad", "quadratic quads");
    case 36:
      return skip("quadratic polygon", "quadratic polygons");
    case 24:
      return volume("quadratic tetrahedron (tetra10)", "quadratic tetrahedra (tetra10)");
    case 25:
    case 29:
    case 33:
      return volume("quadratic hexahedron", "quadratic hexahedra");
    case 26:
    case 31:
    case 32:
      return volume("quadratic wedge", "quadratic wedges");
    case 27:
    case 37:
      return volume("quadratic pyramid", "quadratic pyramids");
    case 42:
      return volume("polyhedron", "polyhedra");
    case 68:
    case 75:
      return skip("higher-order curve", "higher-order curves");
    case 69:
    case 70:
    case 76:
    case 77:
      return skip("higher-order surface cell", "higher-order surface cells");
    case 71:
    case 78:
      return volume("higher-order tetrahedron", "higher-order tetrahedra");
    case 72:
    case 79:
      return volume("higher-order hexahedron", "higher-order hexahedra");
    case 73:
    case 80:
      return volume("higher-order wedge", "higher-order wedges");
    case 74:
    case 81:
      return volume("higher-order pyramid", "higher-order pyramids");
    default:
      break;
  }
  const std::string name = absl::StrCat("cell of VTK type ", vtk_type);
  return CellKind{name, absl::StrCat("cells of VTK type ", vtk_type), CellFate::kUnsupported};
}

}  // namespace tetrefine::io
