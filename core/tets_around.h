#pragma once

// Which tets hold an edge, found through the tets of one of its vertices. Internal to Refine.

#include <cstdint>
#include <vector>

#include "core/counting_sort.h"
#include "core/edge_table.h"
#include "core/fill_later.h"
#include "core/mesh.h"

namespace tetrefine::refine_internal {

// The tets of every vertex (4 entries per tet). A vertex index rather than an edge index (6
// entries per tet and a start per edge): it is built while an iteration's edge table and marks
// are alive, and an edge index made the marking the peak of memory in late iterations
// (bench/peak_memory --max_iterations=3, one thread, 2026-11-25: 142.0 bytes per output tet at
// a1f2968, 166.4 with an edge index, 143.2 with this one; one iteration 85.3, 89.5, 85.7). The
// edges asked about are few (those marked since a pass, or a flagged tet's), so walking their
// vertices' tets costs little.
class TetsAround {
 public:
  // tets: T x 4 vertex indices below num_vertices.
  TetsAround(const std::vector<Tet>& tets, int64_t num_vertices);

  // The tets with an edge in `changed` (ids of `edges`), each once, in increasing order (the
  // order a full pass would meet them in: memory is read forwards). `seen` (T entries) is all
  // zero on entry and on return.
  std::vector<uint32_t> Around(const std::vector<uint32_t>& changed, const EdgeTable& edges,
                               const std::vector<Tet>& tets, FillLater<uint8_t>& seen) const;

  // Calls f(t) for every tet t holding both vertices v and w (the tets around edge v-w), in
  // increasing order. Reads only: safe from many threads at once.
  template <typename F>
  void ForEachOnEdge(uint32_t v, uint32_t w, const std::vector<Tet>& tets, F f) const {
    for (uint64_t i = layout_.start[v]; i < layout_.start[v + 1]; ++i) {
      const uint32_t t = tets_[i];
      const Tet& tet = tets[t];
      if (tet[0] == w || tet[1] == w || tet[2] == w || tet[3] == w) f(t);
    }
  }

 private:
  BucketLayout layout_;
  FillLater<uint32_t> tets_;
};

}  // namespace tetrefine::refine_internal
