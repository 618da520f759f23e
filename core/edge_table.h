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

// The edge table of a refined mesh, built from the table of the mesh it was refined from
// (`before`, for its first before.first.size() - 1 vertices) and what the refinement changed:
//   split          before.size() entries, nonzero for the edges that were split;
//   tet_iteration  T entries; the tets with `made_in` are this refinement's children, every
//                  other tet is a tet of the mesh before, unchanged.
// Equal to BuildEdgeTable(tets, num_points), entry for entry, since (subdivision table, every
// configuration) an edge the refinement made has a new vertex at one end at least, and every edge
// that was not split survives: the kept edges of an old vertex come first in its bucket, in
// their order, and the new ones after them. Only the children's edges are sorted, so an
// iteration that changes a few tets of a large mesh pays a copy of the table instead of a sort of
// every tet's edges. tet_edges is left empty, as by BuildEdgeTable.
// remap (optional): resized to before.size(); remap[e] is the new id of each edge e that was not
// split (UpdateTetEdges reads it), and unspecified for split edges.
EdgeTable UpdateEdgeTable(const EdgeTable& before, const FillLater<uint8_t>& split,
                          const std::vector<Tet>& tets, const std::vector<int32_t>& tet_iteration,
                          int32_t made_in, int64_t num_points,
                          FillLater<uint32_t>* remap = nullptr);

// Where a subdivision put the tets of the mesh before (Subdivide fills it): old tet t became
// children[t] new tets in a row (0: it was kept as it was, as one tet), and the first old tet of
// block b (kBlockSize tets) went to new position block_start[b]. Old tets keep their order.
struct TetSuccession {
  FillLater<uint8_t> children;       // T_before
  std::vector<int64_t> block_start;  // BlockCount(T_before)
};

// Fills table->tet_edges for the tets it was built from. Whatever the array holds on entry is
// overwritten; its memory is reused when it has room (pass the previous iteration's array).
void AddTetEdges(const std::vector<Tet>& tets, EdgeTable* table);

// AddTetEdges for a mesh that a subdivision made (`succession`) from the mesh whose tet edges
// `table->tet_edges` holds on entry, when `table` came from UpdateEdgeTable with `remap`: a kept
// tet's edges are its old edges renamed, and only the children's are looked up. The same array
// as AddTetEdges gives. The array is rewritten in place when the mesh grew by at most an eighth
// (late iterations) and its capacity allows, else written anew (AddTetEdges would reallocate
// there too); AddTetEdges runs when the array on entry is not the mesh before's.
void UpdateTetEdges(const std::vector<Tet>& tets, const TetSuccession& succession,
                    const FillLater<uint32_t>& remap, EdgeTable* table);

}  // namespace tetrefine
