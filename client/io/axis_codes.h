#pragma once

#include <string>

#include "core/volume.h"

namespace tetrefine::io {

// A grid's orientation as imaging tools name it: one letter per index axis i, j, k for the world
// direction (RAS world: R, A, S, or their opposites L, P, I) that axis points to, as nibabel's
// `aff2axcodes` and Slicer's "RAS"/"LPS" do. "LSA": i runs to the left, j up, k to the front.
struct AxisCodes {
  std::string codes;  // three letters, e.g. "RAS"
  // Every index axis lies along a world axis (the direction is a signed permutation: axes flipped
  // or swapped, as most scanners' NIfTI and DICOM files are); false for an oblique grid, whose
  // letters are then each axis's closest world direction.
  bool exact = false;
};

// `direction`: row-major 3 x 3, column c the world direction of index axis c, of any length (a
// GridGeometry::direction, or an affine's linear part with the spacing in it); non-singular.
// Index axes i, j, k in turn take the world axis their column is largest along among those left,
// as nibabel's aff2axcodes does for orthogonal columns (ties: the lower world axis).
AxisCodes AxisCodesOf(const Mat3& direction);

// The word of an axis code letter: "right" for 'R', ... "inferior" for 'I'; "?" otherwise.
const char* AxisCodeWord(char code);

}  // namespace tetrefine::io
