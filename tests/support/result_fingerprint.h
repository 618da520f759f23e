#pragma once

#include <cstdint>

#include "core/refine.h"

namespace tetrefine::testing {

// FNV-1a over the bits of a result's mesh (points, tets, values, labels), per-tet iteration and
// quality, and every iteration's statistics: equal fingerprints mean the same result to the bit.
uint64_t ResultFingerprint(const RefineResult& r);

}  // namespace tetrefine::testing
