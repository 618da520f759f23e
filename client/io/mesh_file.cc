#include "client/io/mesh_file.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_join.h"
#include "client/io/io_error.h"
#include "client/io/label_names.h"

namespace tetrefine::io {

absl::string_view FrameTag(MeshFrame frame) {
  switch (frame) {
    case MeshFrame::kRas:
      return "RAS";
    case MeshFrame::kLps:
      return "LPS";
    case MeshFrame::kUntagged:
      break;
  }
  return "";
}

std::string DroppedArray(bool point_data, absl::string_view name) {
  return absl::StrCat(point_data ? "point" : "cell", " data \"", name, "\"");
}

std::string SkippedCellsText(const MeshFile& file) {
  std::vector<std::string> kinds;
  for (const auto& [kind, count] : file.skipped_cells)
    kinds.push_back(absl::StrCat(kind, ": ", count));
  return absl::StrJoin(kinds, ", ");
}

void DropNonFiniteDerivedArrays(MeshFile* file) {
  std::vector<double>& values = file->mesh.values;
  const auto bad_value =
      std::find_if(values.begin(), values.end(), [](double x) { return !std::isfinite(x); });
  if (bad_value != values.end()) {
    file->dropped_arrays.push_back(absl::StrCat(DroppedArray(true, "value"),
                                                " (not finite at vertex ",
                                                bad_value - values.begin(), ": ", *bad_value, ")"));
    values.clear();
  }
  std::vector<float>& quality = file->tet_quality;
  const auto bad_quality =
      std::find_if(quality.begin(), quality.end(), [](float x) { return !std::isfinite(x); });
  if (bad_quality != quality.end()) {
    file->dropped_arrays.push_back(
        absl::StrCat(DroppedArray(false, "quality"), " (not finite at tet ",
                     bad_quality - quality.begin(), ": ", *bad_quality, ")"));
    quality.clear();
  }
}

std::string LabelArrayName(const MeshFile& file) {
  return file.label_name.empty() ? std::string("label") : file.label_name;
}

absl::Status ValidateMeshFile(const MeshFile& file, absl::string_view path) {
  const Mesh& mesh = file.mesh;
  const size_t v = mesh.points.size();
  const size_t t = mesh.tets.size();
  if (v > std::numeric_limits<uint32_t>::max()) {
    return FileError(path, absl::StrCat(v, " vertices is more than 32-bit indices address"));
  }
  if (!mesh.values.empty() && mesh.values.size() != v) {
    return FileError(path, absl::StrCat("point data \"value\" has ", mesh.values.size(),
                                        " entries for ", v, " vertices"));
  }
  if (!file.tet_iteration.empty() && file.tet_iteration.size() != t) {
    return FileError(path, absl::StrCat("cell data \"iteration\" has ", file.tet_iteration.size(),
                                        " entries for ", t, " tetrahedra"));
  }
  if (!file.tet_quality.empty() && file.tet_quality.size() != t) {
    return FileError(path, absl::StrCat("cell data \"quality\" has ", file.tet_quality.size(),
                                        " entries for ", t, " tetrahedra"));
  }
  // A name is a line of a .msh file: a control character (a line break) would end it early. A
  // quote is kept: Gmsh 4.8 writes `"white matter "WM""` unescaped (and reads its own name back
  // only to the inner quote, "white matter "; meshio drops the inner quotes); our reader takes
  // the line's first quote to its last, the whole name, and writes it back as Gmsh wrote it.
  // Refusing it refused Gmsh's own files (found by a file-format sweep).
  for (const auto& [label, name] : file.region_names) {
    for (const char c : name) {
      if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f) {
        return FileError(path,
                         absl::StrCat("the name of region ", label, " holds a control character"));
      }
    }
  }
  // A label name must be one readers recognise (label_names.h), or labels written under it
  // would come back as an anonymous cell array.
  if (!file.mesh.labels.empty() && !file.label_name.empty() && LabelNameRank(file.label_name) < 0) {
    return FileError(path, absl::StrCat("label name \"", file.label_name,
                                        "\" is not one of the names readers recognise as labels "
                                        "(gmsh:physical, medit:ref, CellEntityIds, region, ...)"));
  }
  if (!file.mesh.labels.empty() && file.mesh.labels.size() != t) {
    return FileError(
        path, absl::StrCat("cell data \"", LabelArrayName(file), "\" has ", file.mesh.labels.size(),
                           " entries for ", t, " tetrahedra"));
  }
  for (size_t i = 0; i < v; ++i) {
    for (int a = 0; a < 3; ++a) {
      if (!std::isfinite(mesh.points[i][a])) {
        return FileError(path, absl::StrCat("vertex ", i, " has a non-finite coordinate (",
                                            mesh.points[i][a], ")"));
      }
    }
  }
  for (size_t i = 0; i < mesh.values.size(); ++i) {
    if (!std::isfinite(mesh.values[i])) {
      return FileError(
          path, absl::StrCat("value of vertex ", i, " is not finite (", mesh.values[i], ")"));
    }
  }
  for (size_t i = 0; i < t; ++i) {
    for (int c = 0; c < 4; ++c) {
      if (mesh.tets[i][c] >= v) {
        return FileError(path, absl::StrCat("tetrahedron ", i, " uses vertex ", mesh.tets[i][c],
                                            ", out of range for ", v, " vertices"));
      }
    }
  }
  for (size_t i = 0; i < file.tet_quality.size(); ++i) {
    if (!std::isfinite(file.tet_quality[i])) {
      return FileError(path, absl::StrCat("quality of tetrahedron ", i, " is not finite"));
    }
  }
  return absl::OkStatus();
}

}  // namespace tetrefine::io
