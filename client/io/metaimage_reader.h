#pragma once

#include <string>

#include "absl/status/statusor.h"
#include "client/io/volume_file.h"

namespace tetrefine::io {

// Reads a 3D MetaImage volume: .mha (header and data in one file) or .mhd with its data file,
// binary, optionally zlib-compressed, either byte order; element types MET_UCHAR, MET_SHORT,
// MET_USHORT, MET_INT, MET_FLOAT, MET_DOUBLE, and MET_CHAR, MET_UINT, MET_LONG and MET_ULONG (4
// bytes, as in MetaIO), MET_LONG_LONG, MET_ULONG_LONG widened exactly (DecodeVoxels); one channel.
// Geometry from ElementSpacing, Offset and TransformMatrix (each row of which is one index axis's
// direction, as ITK reads it). Frame: MetaImage coordinates are LPS (ITK's convention, whatever
// AnatomicalOrientation says); they are converted to RAS by negating x and y, so the result is in
// world RAS mm like every VolumeFile.
absl::StatusOr<VolumeFile> ReadMetaImage(const std::string& path);

}  // namespace tetrefine::io
