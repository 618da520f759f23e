#pragma once

#include <string>

#include "absl/status/statusor.h"
#include "client/io/volume_file.h"

namespace tetrefine::io {

// Reads a 3D NRRD volume (.nrrd with attached data, or .nhdr with a single "data file"), raw,
// gzip or ascii encoding, either endianness; sample types uchar, short, ushort, int, float,
// double, and signed char, uint, longlong, ulonglong widened exactly (DecodeVoxels), each in every
// spelling teem takes. Geometry from "space directions" + "space origin", else from "spacings" at
// origin 0. Frame: NRRD states its space; "left-posterior-superior" (LPS, what ITK/Slicer write)
// and "left-anterior-superior" are converted to RAS by negating x and y (x only for LAS), so the
// result is in world RAS mm like every VolumeFile. Files without a space are taken as given.
absl::StatusOr<VolumeFile> ReadNrrd(const std::string& path);

}  // namespace tetrefine::io
