// Reading VTK XML unstructured grids (.vtu) with pugixml. See vtu_format.h for what is read.
#include <algorithm>
#include <string>
#include <utility>
#include <vector>

#include "absl/strings/match.h"
#include "absl/strings/str_cat.h"
#include "client/io/io_error.h"
#include "client/io/label_names.h"
#include "client/io/mesh_frame.h"
#include "client/io/number_text.h"
#include "client/io/pvtu_reader.h"
#include "client/io/vtk_cells.h"
#include "client/io/vtk_xml_file.h"
#include "client/io/vtu_data_array.h"
#include "client/io/vtu_format.h"
#include "core/huge_pages.h"
#include "pugixml.hpp"

namespace tetrefine::io {
namespace {

bool AttributeInt(pugi::xml_node node, const char* key, int64_t& out) {
  const pugi::xml_attribute a = node.attribute(key);
  return a && ParseInt64(a.value(), out);
}

int64_t Components(pugi::xml_node node) {
  int64_t n = 1;
  if (node.attribute("NumberOfComponents") && !AttributeInt(node, "NumberOfComponents", n)) {
    return -1;
  }
  return n;
}

// The frame named by a "SPACE" string array in field data (what 3D Slicer writes).
absl::StatusOr<MeshFrame> FieldDataFrame(pugi::xml_node grid, VtuArrayReader& arrays) {
  for (pugi::xml_node array : grid.child("FieldData").children()) {
    if (absl::string_view(array.attribute("Name").value()) != "SPACE") continue;
    absl::StatusOr<std::string> bytes = arrays.StringBytes(array);
    if (!bytes.ok()) return bytes.status();
    const absl::string_view first(bytes->c_str());  // up to the first NUL
    if (absl::StrContains(first, "LPS")) return MeshFrame::kLps;
    if (absl::StrContains(first, "RAS")) return MeshFrame::kRas;
  }
  return MeshFrame::kUntagged;
}

// One <Piece> of the grid as a mesh of its own (its points numbered from 0).
absl::StatusOr<MeshFile> ParsePiece(const VtkXmlFile& xml, pugi::xml_node piece,
                                    absl::string_view path) {
  const auto line_of = [&xml](pugi::xml_node node) { return xml.LineOf(node); };
  const pugi::xml_node grid = xml.dataset;
  int64_t v = -1;
  int64_t n = -1;
  if (!AttributeInt(piece, "NumberOfPoints", v) || !AttributeInt(piece, "NumberOfCells", n) ||
      v < 0 || v > int64_t{0xffffffff} || n < 0 || n > (int64_t{1} << 40)) {
    return FileLineError(path, line_of(piece),
                         "Piece needs valid NumberOfPoints and NumberOfCells");
  }

  VtuArrayReader arrays(path, xml.encoding, xml.appended, line_of);
  MeshFile file;
  absl::StatusOr<MeshFrame> frame = FieldDataFrame(grid, arrays);
  if (!frame.ok()) return frame.status();
  file.frame = *frame;

  const pugi::xml_node points_array = piece.child("Points").child("DataArray");
  if (!points_array) return FileError(path, "no <Points><DataArray>");
  if (Components(points_array) != 3) {
    return FileLineError(path, line_of(points_array), "Points DataArray must have 3 components");
  }
  absl::StatusOr<std::vector<double>> xyz = arrays.Doubles(points_array, 3 * v);
  if (!xyz.ok()) return xyz.status();
  ReserveHuge(file.mesh.points, v);
  file.mesh.points.resize(v);
  for (int64_t i = 0; i < v; ++i) {
    file.mesh.points[i] = {(*xyz)[3 * i], (*xyz)[3 * i + 1], (*xyz)[3 * i + 2]};
  }
  xyz->clear();
  xyz->shrink_to_fit();

  const pugi::xml_node cells = piece.child("Cells");
  if (!cells) return FileError(path, "no <Cells>");
  pugi::xml_node connectivity_array, offsets_array, types_array;
  for (pugi::xml_node child : cells.children("DataArray")) {
    const absl::string_view name = child.attribute("Name").value();
    if (name == "connectivity") connectivity_array = child;
    if (name == "offsets") offsets_array = child;
    if (name == "types") types_array = child;
  }
  if (!connectivity_array || !offsets_array || !types_array) {
    return FileLineError(path, line_of(cells),
                         "Cells needs connectivity, offsets and types arrays");
  }
  VtkCells vtk;
  absl::StatusOr<std::vector<int64_t>> offsets = arrays.Int64s(offsets_array, n);
  if (!offsets.ok()) return offsets.status();
  absl::StatusOr<std::vector<int64_t>> types = arrays.Int64s(types_array, n);
  if (!types.ok()) return types.status();
  // XML offsets are cell ends; VtkCells wants a leading 0.
  const int64_t connectivity_size = n == 0 ? 0 : offsets->back();
  if (connectivity_size < 0 || connectivity_size > (int64_t{1} << 44)) {
    return FileLineError(path, line_of(offsets_array), "last cell offset is out of range");
  }
  absl::StatusOr<std::vector<int64_t>> connectivity =
      arrays.Int64s(connectivity_array, connectivity_size);
  if (!connectivity.ok()) return connectivity.status();
  vtk.offsets.reserve(n + 1);
  vtk.offsets.push_back(0);
  vtk.offsets.insert(vtk.offsets.end(), offsets->begin(), offsets->end());
  vtk.types = *std::move(types);
  vtk.connectivity = *std::move(connectivity);

  VtkCellData cell_data;
  for (pugi::xml_node child : piece.child("CellData").children("DataArray")) {
    const std::string name = child.attribute("Name").value();
    if (Components(child) != 1) {
      file.dropped_arrays.push_back(DroppedArray(false, name));
      continue;
    }
    if (IsGhostArrayName(name)) {
      absl::StatusOr<std::vector<int64_t>> flags = arrays.Int64s(child, n);
      if (!flags.ok()) return flags.status();
      if (absl::Status s = GhostCellFlags(name, *flags, path, &cell_data); !s.ok()) return s;
      continue;
    }
    if (name == "iteration" || name == "quality") {
      absl::StatusOr<std::vector<double>> values = arrays.Doubles(child, n);
      if (!values.ok()) return values.status();
      (name == "iteration" ? cell_data.iteration : cell_data.quality) = *std::move(values);
      continue;
    }
    const int rank = LabelNameRank(name);
    if (rank < 0 || (cell_data.label_rank >= 0 && rank >= cell_data.label_rank)) {
      file.dropped_arrays.push_back(DroppedArray(false, name));
      continue;
    }
    absl::StatusOr<std::vector<int64_t>> labels = arrays.Int64s(child, n);
    if (!labels.ok()) return labels.status();
    // A label array the file prefers (LabelNameRank) replaces one read before.
    if (cell_data.label_rank >= 0) {
      file.dropped_arrays.push_back(DroppedArray(false, cell_data.label_name));
    }
    cell_data.label = *std::move(labels);
    cell_data.label_name = name;
    cell_data.label_rank = rank;
  }
  for (pugi::xml_node child : piece.child("PointData").children("DataArray")) {
    // Ghost points are the points of ghost cells, which go (CellsToTets); a point shared with
    // another piece is merged by its coordinates (MergePvtuPieces): nothing to carry.
    if (IsGhostArrayName(child.attribute("Name").value())) continue;
    if (absl::string_view(child.attribute("Name").value()) != "value" || Components(child) != 1) {
      file.dropped_arrays.push_back(DroppedArray(true, child.attribute("Name").value()));
      continue;
    }
    absl::StatusOr<std::vector<double>> values = arrays.Doubles(child, v);
    if (!values.ok()) return values.status();
    file.mesh.values = *std::move(values);
  }
  if (absl::Status s = CellsToTets(vtk, cell_data, v, path, file); !s.ok()) return s;
  FrameToRas(file);
  DropNonFiniteDerivedArrays(&file);
  return file;
}

}  // namespace

absl::StatusOr<MeshFile> ParseVtu(absl::string_view text, absl::string_view path) {
  VtkXmlFile xml;
  if (absl::Status s = OpenVtkXml(text, path, "UnstructuredGrid", xml); !s.ok()) return s;
  std::vector<MeshFile> pieces;
  for (pugi::xml_node piece : xml.dataset.children("Piece")) {
    absl::StatusOr<MeshFile> file = ParsePiece(xml, piece, path);
    if (!file.ok()) return file.status();
    pieces.push_back(*std::move(file));
  }
  if (pieces.empty()) return FileError(path, "no <Piece>");
  // Several pieces in one file (vtkXMLUnstructuredGridWriter with SetNumberOfPieces, which
  // VTK and ParaView read) are one mesh whose shared points each piece repeats: merged as a
  // .pvtu's pieces are. They were refused (found by a file-format sweep).
  const std::vector<std::string> names(pieces.size(), std::string(path));
  absl::StatusOr<MeshFile> file = pieces.size() == 1
                                      ? absl::StatusOr<MeshFile>(std::move(pieces[0]))
                                      : MergePvtuPieces(std::move(pieces), names);
  if (!file.ok()) return file.status();
  if (absl::Status s = ValidateMeshFile(*file, path); !s.ok()) return s;
  return file;
}

}  // namespace tetrefine::io
