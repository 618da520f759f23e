#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "absl/status/status.h"
#include "absl/strings/string_view.h"
#include "core/mesh.h"

namespace tetrefine::io {

// The world frame a mesh file says its coordinates are in. 3D Slicer tags the files it writes
// ("SPACE=LPS" in a legacy VTK header, a "SPACE" string array in VTU field data); other tools
// write no tag. tetrefine works in RAS (see VolumeFile), so readers negate x and y of an LPS file
// and writers negate them back, writing the same tag: a file goes out in the frame it came in.
enum class MeshFrame {
  kUntagged,  // no tag: coordinates are taken as RAS, and written without a tag
  kRas,       // tagged SPACE=RAS
  kLps,       // tagged SPACE=LPS: stored x and y are the negated RAS x and y
};

// "RAS", "LPS" or "" (untagged).
absl::string_view FrameTag(MeshFrame frame);

// A tetrahedral mesh as stored in a file: the core Mesh plus optional per-tet arrays.
//   mesh.points:   V x 3 world coordinates, RAS (mm for imaging data) whatever `frame` says.
//   mesh.tets:     T x 4 zero-based vertex indices.
//   mesh.values:   V scalars, or empty when the file has no "value" point data.
//   tet_iteration: T integers (the refinement iteration that created each tet), or empty.
//   tet_quality:   T quality measures, or empty.
//   mesh.labels:   T region labels (Gmsh physical group, Medit reference, a VTK cell array such
//                  as "region" or "CellEntityIds"), or empty. Core refinement passes them on
//                  to every child tet.
//   label_name:    what the input called mesh.labels: "gmsh:physical", "medit:ref", or the VTK
//                  cell array's name; one of the names LabelNameRank recognises, or empty.
//                  Writers of VTK formats use it as the array name ("label" when empty); Gmsh
//                  and Medit store labels in their own slots whatever the name.
//   frame:         the frame tag of the file read, and the one to write.
//   dropped_arrays: what a reader saw and did not keep, e.g. `point data "temperature"` or
//                  `cell data "density"` (VTK formats), in file order; writers ignore it. The
//                  CLI says so, since a refined file will not have them.
struct MeshFile {
  tetrefine::Mesh mesh;
  std::vector<int32_t> tet_iteration;
  std::vector<float> tet_quality;
  // Default member initializers: designated initializers that predate these members (e.g.
  // {.mesh = m, .tet_iteration = {}, .tet_quality = {}}) stay warning-free.
  std::string label_name{};
  MeshFrame frame = MeshFrame::kUntagged;
  std::vector<std::string> dropped_arrays{};
  // Names of labels (Gmsh $PhysicalNames of dimension 3), for the formats that keep them: .msh
  // writes them back. Without control characters (a name is one line of a .msh file); quotes
  // are kept as Gmsh keeps them.
  std::map<int32_t, std::string> region_names{};
  // Cells a VTK file marked as ghosts (copies of another piece's cells, vtkGhostType), which the
  // reader skipped (io::CellsToTets); the CLI says how many.
  int64_t ghost_cells_skipped = 0;
  // Points, lines and surface cells the reader skipped: counts by kind, {"triangles": 180}
  // (CellCensus::SkippedCells), e.g. a Gmsh file's boundary triangles of a physical surface.
  // Refinement has no use for them and the output does not have them, which the CLI says (an
  // outside review, 2026-11-29, found their loss silent).
  std::map<std::string, int64_t> skipped_cells{};
};

// "point data \"name\"" or "cell data \"name\"": an entry of MeshFile::dropped_arrays.
std::string DroppedArray(bool point_data, absl::string_view name);

// MeshFile::skipped_cells as text, "triangles: 180, lines: 1" (kinds in name order); empty when
// none was skipped.
std::string SkippedCellsText(const MeshFile& file);

// What readers do with a "value" point array or a "quality" cell array holding a NaN or an
// infinity: they are derived data (refine and verify sample the volume and measure the tets
// again), so such an array is dropped, and named in dropped_arrays with its first bad entry,
// rather than refusing a usable mesh (a CLI sweep found refine, verify and info all refusing
// one). ValidateMeshFile still refuses them in what is written.
void DropNonFiniteDerivedArrays(MeshFile* file);

// Name of the label array VTK writers use: label_name, or "label" when that is empty.
std::string LabelArrayName(const MeshFile& file);

// OK when every array has its documented length (or is empty where allowed), every index is
// below V (and V fits uint32), every coordinate, value and quality is finite, and label_name is
// empty or a recognised label name. The message
// starts with `path` and names the first offending entry.
absl::Status ValidateMeshFile(const MeshFile& file, absl::string_view path);

}  // namespace tetrefine::io
