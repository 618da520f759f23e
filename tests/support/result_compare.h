#pragma once

// Bitwise comparison of meshes and refinement results, for the tests that prove two paths
// (core and service, sharded and not, any thread count) give the same bits.

#include "core/mesh.h"
#include "core/refine.h"

namespace tetrefine::testing {

// Each records a GoogleTest failure per difference; doubles are compared as bit patterns, so
// -0.0 != 0.0 and NaN == NaN: "identical" means identical.
void ExpectSameMesh(const Mesh& expected, const Mesh& actual);
void ExpectSameStats(const IterationStats& expected, const IterationStats& actual);
// Everything but wall times.
void ExpectSameResult(const RefineResult& expected, const RefineResult& actual);

}  // namespace tetrefine::testing
