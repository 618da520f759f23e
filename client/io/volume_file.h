#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "core/volume.h"

namespace tetrefine::io {

// A 4x4 homogeneous transform, row-major: world = affine * (i, j, k, 1).
using Affine = std::array<std::array<double, 4>, 4>;

// The largest size of one volume axis any reader accepts: a header claiming more is corrupt,
// and refusing it early keeps a hostile header from sizing a huge allocation.
inline constexpr int64_t kMaxVolumeAxis = int64_t{1} << 20;

// A volume read from a file.
//
// World frame: RAS millimetres, as NIfTI defines it (+x = Right, +y = Anterior, +z = Superior).
// This is deliberately NOT ITK's LPS: NIfTI is the main input, and staying in its frame means a
// mesh made in FSL/FreeSurfer/nibabel world coordinates lines up without conversion. Readers of
// LPS formats (NRRD, MetaImage) negate x and y to land in the same frame.
//
// Frame rules:
//  - When the file's index-to-world affine is diagonal up to axis signs, the samples are reordered
//    (flipped along every axis with a negative scale) so that `volume` is axis-aligned with
//    positive spacing (identity direction) and exact in world RAS mm: volume.Sample(p) is the
//    file's value at world point p. Such volumes give the same bits as before directions existed.
//  - When the affine rotates, shears or permutes axes ("oblique"), `volume` keeps the file's
//    sample order; its origin is the affine's translation, its spacing the affine's column
//    lengths and its direction the normalised columns. It is exact in world RAS mm too: a mesh
//    in scanner coordinates lines up with it.
struct VolumeFile {
  Volume volume;
  // Human-readable notes about approximations made while reading (each names the file).
  std::vector<std::string> warnings;
  // The file's own index-to-world (RAS mm) transform, indices in the file's storage order,
  // before any flip. Identity-like for files without orientation information.
  Affine affine{};
};

}  // namespace tetrefine::io
