#pragma once

// The service tests' long request: 135k input tets with a tolerance no edge meets, so that,
// uncancelled and unlimited, it refines for seconds towards a 20-million-tet budget. The
// admission and cancellation tests stop it on purpose.

#include "client/refine_client.h"
#include "core/mesh.h"
#include "core/volume.h"
#include "tests/support/geometry.h"

namespace tetrefine::testing {

struct HeavyCase {
  Volume volume = TestVolume({64, 64, 64});
  Mesh mesh = FiveTetMesh({1.0, 1.0, 1.0}, {61.0, 61.0, 61.0}, {30, 30, 30});
  client::RefineRequestOptions options = [] {
    client::RefineRequestOptions o;
    o.refine.epsilon = 1e-6;
    o.refine.max_iterations = 4;
    o.SetMaxTets(20'000'000);
    o.refine.lattice_n = 0;
    o.skip_final_mesh = true;
    return o;
  }();
};

// Built once, on first use.
inline const HeavyCase& Heavy() {
  static const HeavyCase* heavy = new HeavyCase();
  return *heavy;
}

}  // namespace tetrefine::testing
