#pragma once

#include <array>

#include "core/volume.h"

namespace tetrefine::render {

// The value range a figure's colour map spans: the 0.5th to the 99.5th percentile of the
// volume's samples (every sample up to a million, else an even stride through them), or the
// whole range when those coincide.
//
// Why not min to max: a handful of outliers set the extremes of real scans. In the bundled MRI
// (examples/anatomical_33x41x25.nii) the samples span [-610, 30393] but 99% of them lie in
// [751, 13015], so min-max colouring spends 60% of the map on 0.5% of the voxels and the brain
// comes out in one colour. Samples beyond the range take the end colours.
std::array<double, 2> DisplayRange(const Volume& volume);

}  // namespace tetrefine::render
