#pragma once

#include "core/volume.h"

namespace tetrefine::reproduce {

// Otsu's threshold of the volume's samples (256 bins between its minimum and maximum): the value
// that best separates them into two classes by between-class variance. For the head MRIs it
// separates the head from the air around it, which is how the masks of the block meshes are made.
double OtsuThreshold(const Volume& volume);

}  // namespace tetrefine::reproduce
