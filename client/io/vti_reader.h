#pragma once

#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "absl/strings/string_view.h"
#include "client/io/volume_file.h"

namespace tetrefine::io {

// Reads a VTK XML image (.vti: <VTKFile type="ImageData">), what ParaView's "Save Data" and
// vtkXMLImageDataWriter write for a volume. The samples are the point data array named by
// <PointData Scalars="...">, else the first one-component point data array; they may be stored
// in every form the .vtu reader reads (ascii, inline base64, appended raw or base64; zlib, lzma
// or lz4 blocks; UInt32 or UInt64 headers; either byte order), in one <Piece> or several that
// tile WholeExtent. Types: UInt8, Int16, UInt16, Int32, Float32 and Float64 are kept as they are;
// Int8, UInt32, Int64 and UInt64 are widened exactly over the whole image (DecodeVoxels: int16;
// int32 or float64, or an error naming the largest magnitude); ascii arrays are read as float64.
//
// Geometry: sample (i, j, k) of the extent lies at Origin + Direction (Spacing * (i, j, k)), as
// vtkImageData places it (Direction, row-major, is VTK 9's; identity when absent), and the
// extent need not start at 0. VTK images carry no anatomical frame: like .vtu meshes, their
// coordinates are taken as world RAS mm. A rotated Direction gives an oblique volume (see
// VolumeFile).
//
// Errors name the file and, for an array, its line and name: another dataset type, a missing
// or malformed WholeExtent, Origin, Spacing or Direction, an extent of fewer than 2 samples on an
// axis, pieces that leave samples uncovered, no one-component point data (cell data and vector
// arrays are named), and whatever the array decoding finds.
absl::StatusOr<VolumeFile> ParseVti(absl::string_view text, absl::string_view path);
absl::StatusOr<VolumeFile> ReadVti(const std::string& path);

// Reads a parallel VTK image (.pvti: <PImageData>, what vtkXMLPImageDataWriter and ParaView's
// parallel "Save Data" write): the grid from the index (WholeExtent, Origin, Spacing, Direction)
// and the samples from the .vti files its <Piece Source="..."> elements name (relative to the
// index's directory), each piece placed by its own Extent, as for a several-piece .vti. An index
// without Direction takes its pieces' (VTK 9.1 writes it only there), which must agree. Errors
// name the index or the piece file.
absl::StatusOr<VolumeFile> ReadPvti(const std::string& path);

// The piece files a .pvti index names, in order, resolved against the directory of `path`, after
// checking the index's grid as ReadPvti does (for the fuzz target; ReadPvti reads the pieces).
absl::StatusOr<std::vector<std::string>> ParsePvtiIndex(absl::string_view text,
                                                        absl::string_view path);

}  // namespace tetrefine::io
