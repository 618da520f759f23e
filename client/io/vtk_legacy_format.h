#pragma once

#include <string>

#include "absl/status/statusor.h"
#include "absl/strings/string_view.h"
#include "client/io/mesh_file.h"
#include "client/io/volume_file.h"

namespace tetrefine::io {

// Legacy VTK .vtk, DATASET UNSTRUCTURED_GRID, ASCII or BINARY (big-endian). A STRUCTURED_POINTS
// file is an error that says it is a volume (ParseVtkLegacyImage reads it).
//
// Reads file versions 2.x-4.x (CELLS with a count per cell) and 5.x (OFFSETS/CONNECTIVITY, any
// integer type) as VTK 9, ParaView, meshio and 3D Slicer write them; METADATA blocks (after
// POINTS or an array) are skipped. Keeps linear tetrahedra (type 10); points, lines and surface
// cells are skipped; other volume cells are an error naming what the file holds. Point data
// "value", cell data "iteration"/"quality" and the region labels (the array LabelNameRank
// prefers) come from SCALARS or FIELD arrays; other attributes are skipped. The frame comes from
// "SPACE=LPS"/"SPACE=RAS" in the title line (how Slicer tags the files it writes) or a dataset
// FIELD string array "SPACE"; LPS points are converted to RAS.
absl::StatusOr<MeshFile> ParseVtkLegacy(absl::string_view text, absl::string_view path);

// Legacy VTK DATASET STRUCTURED_POINTS (an image: what vtkStructuredPointsWriter, ParaView and
// ITK's VTKImageIO write for a volume), ASCII or BINARY, versions 2 to 5.1, as a volume. The
// samples are the first one-component POINT_DATA array (SCALARS or FIELD), whatever its name;
// other attributes and cell data are skipped. Sample (i, j, k) lies at ORIGIN + DIRECTION
// (SPACING * (i, j, k)) (ASPECT_RATIO is SPACING's old name; DIRECTION, row-major, is optional);
// like meshes, the coordinates are RAS unless the title says SPACE=LPS (then converted). The
// file's type is kept where a volume has it (unsigned_char, short, unsigned_short, int, float);
// binary char, unsigned_int, long and unsigned_long (and the vtktype names) are widened exactly
// (DecodeVoxels); ASCII values keep the type (int16 for char, int32 for 32- and 64-bit integers)
// where every one fits it, float64 otherwise, and 32- and 64-bit integers beyond 2^53 are
// refused as DecodeVoxels refuses them. Errors name the file
// and line: an UNSTRUCTURED_GRID (a mesh), fewer than 2 samples on an axis, no samples.
absl::StatusOr<VolumeFile> ParseVtkLegacyImage(absl::string_view text, absl::string_view path);
absl::StatusOr<VolumeFile> ReadVtkLegacyImage(const std::string& path);

// Whether the legacy .vtk file at `path` is a STRUCTURED_POINTS image (its DATASET line says so);
// false for a mesh, another dataset or a file that cannot be read.
bool IsVtkLegacyImage(const std::string& path);

struct VtkLegacyWriteOptions {
  bool binary = false;  // BINARY (big-endian raw values) instead of ASCII
};

// Writes version 4.2 (what Slicer writes, readable by every VTK since 6, ParaView and meshio), or
// 5.1 with 64-bit connectivity when vertex indices exceed 32-bit signed range: POINTS double,
// CELLS/CELL_TYPES 10, POINT_DATA SCALARS value double, CELL_DATA SCALARS iteration int, quality
// float and the labels int (named LabelArrayName, '%'-escaped as VTK escapes names), each only
// when the MeshFile has it. A tagged frame goes into the title ("tetrefine mesh SPACE=LPS"),
// with the points in that frame.
std::string FormatVtkLegacy(const MeshFile& file, const VtkLegacyWriteOptions& options = {});

}  // namespace tetrefine::io
