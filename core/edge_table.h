#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "core/fill_later.h"
#include "core/mesh.h"

namespace tetrefine {

// The unique edges of a tet mesh, each listed once, ordered by (smaller endpoint, larger
// endpoint): an order that depends only on the mesh, never on threads.
struct EdgeTable {
  FillLater<uint32_t> first;  // V + 1: edges whose smaller endpoint is v are [first[v], first[v+1])
  FillLater<uint32_t> second;                    // E: the larger endpoint of each edge
  FillLater<std::array<uint32_t, 6>> tet_edges;  // T x 6: edge ids in kTetEdges order (AddTetEdges)

  int64_t size() const { return static_cast<int64_t>(second.size()); }
  // Smaller endpoint of edge e (binary search over `first`).
  uint32_t FirstOf(uint32_t e) const;
};

// Lists the unique edges (first, second) in O(T) work plus small per-vertex sorts, in parallel
// on the current arena. Indices must be valid (the mesh validated). tet_edges is left empty:
// evaluating edges does not need it, and the last evaluation of a run subdivides nothing.
EdgeTable BuildEdgeTable(const std::vector<Tet>& tets, int64_t num_points);

// Fills table->tet_edges for the tets it was built from. Whatever the array holds on entry is
// overwritten; its memory is reused when it has room (pass the previous iteration's array).
void AddTetEdges(const std::vector<Tet>& tets, EdgeTable* table);

}  // namespace tetrefine
