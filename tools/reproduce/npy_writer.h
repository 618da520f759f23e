#pragma once

#include <string>

#include "core/volume.h"

namespace tetrefine::reproduce {

// The samples of `volume` as a NumPy .npy file (format 1.0): float64 little-endian, C order,
// shape (nz, ny, nx), so that array[k, j, i] is volume.At(i, j, k). Every voxel type converts to
// float64 exactly, so a reader samples the same values core does.
std::string VolumeNpy(const Volume& volume);

}  // namespace tetrefine::reproduce
