#pragma once

#include <array>

#include "client/io/volume_file.h"
#include "core/volume.h"

namespace tetrefine::io {

// The affine whose column j is `axes[j]` (the world step of one sample along index axis j) and
// whose translation is `origin` (the world position of sample (0, 0, 0)).
inline Affine AffineFromAxes(const std::array<Vec3, 3>& axes, const Vec3& origin) {
  Affine affine{};
  for (int row = 0; row < 3; ++row) {
    for (int column = 0; column < 3; ++column) affine[row][column] = axes[column][row];
    affine[row][3] = origin[row];
  }
  affine[3][3] = 1.0;
  return affine;
}

// Converts an index-to-LPS affine (ITK, DICOM, NRRD "left-posterior-superior", MetaImage) to
// index-to-RAS: LPS and RAS differ by the sign of world x and y.
inline Affine LpsToRas(Affine affine) {
  for (int row = 0; row < 2; ++row) {
    for (int column = 0; column < 4; ++column) affine[row][column] = -affine[row][column];
  }
  return affine;
}

}  // namespace tetrefine::io
