#pragma once

// Sharding for the schemes whose decisions read the tets around an edge (the longest-edge
// closure and quality guard, certified mode): one iteration at a time, each part sent with a
// halo of neighbouring tets wide enough that its own tets are decided as in the whole mesh.

#include <cstdint>
#include <vector>

#include "absl/status/statusor.h"
#include "core/mesh.h"
#include "core/refine.h"
#include "sharding/mesh_partition.h"

namespace tetrefine::sharding {

// Rings of vertex-adjacent tets a part carries around the tets it owns. Why 29: in one
// iteration a split flag travels at most one ring per closure round and per guard round (a
// closure round marks edges of the tet, or of a face of it, whose marks it read; the edge test
// and the certify lattice test read one edge or one tet), and two in the guard's last look (it
// marks edges of a tet from the marks of the tets around them), 8 + 2 * (1 + 8) + 2 = 28 rings
// for the longest-edge scheme (SchemeRules in core/refine.cc), so a tet 28 rings out is the
// farthest whose edges can change an owned tet's pattern; one more ring for margin.
// tests/sharding/halo_parts_test.cc shows that too narrow a halo changes the result.
inline constexpr int kHaloRings = 29;

// A part with a halo: mesh.tets are the owned tets and the halo tets in ascending whole-mesh
// order; owned[t] says which are the part's own. input_vertex / input_tet map to the whole mesh.
struct HaloPart {
  MeshPart part;
  std::vector<uint8_t> owned;  // per local tet
};

// Each of `groups` (a partition of the tets, from PartitionTets) grown by `rings` rings of tets
// that share a vertex with the ring before, then extracted as a mesh (labels kept).
std::vector<HaloPart> ExtractHaloParts(const Mesh& mesh,
                                       const std::vector<std::vector<uint32_t>>& groups, int rings);

// The whole mesh between iterations, with what the unsharded Refine carries per tet.
struct WholeMesh {
  Mesh mesh;                           // points, values (sampled), tets, labels (or empty)
  std::vector<int32_t> tet_iteration;  // iteration that created each tet
  std::vector<float> tet_quality;      // mean ratio of each tet
  std::vector<uint32_t> tet_parent;    // input tet each tet lies in
};

// One applied iteration, assembled from each part's result of one iteration (refined with
// track_parents): the children of owned tets only, vertices unified by their coordinate bits (a
// midpoint is computed from the same two endpoints in every part, so it has the same bits).
// The statistics are those of the whole iteration, counted on the whole mesh (a halo tet's
// split is not counted).
struct MergedIteration {
  WholeMesh whole;
  int64_t split_tets = 0;                // tets that were split (NTwE)
  int64_t split_edges = 0;               // edges of `before` whose midpoint is a new vertex
  int64_t steiner_points = 0;            // new vertices that are no edge's midpoint (SP)
  ConfigurationCounts configurations{};  // tets by configuration, from their split edges
  // Split tets cut by another tiling than Table 1's (IterationStats::other_tilings), with
  // best_tilings; 0 without.
  int64_t other_tilings = 0;
  double worst_new_quality = 1.0;  // over the new tets: min mean ratio (-1: degenerate)
};

// `before` is the mesh the parts were cut from; results[p] the result of parts[p] after at most
// one iteration (0 iterations: unchanged). New tets get iteration `iteration`. best_tilings: the
// parts cut each tet by its best tiling (the longest-edge scheme), which the merge finds again
// from the tet's corners and split edges to count other_tilings. INTERNAL when a
// result does not start with its part's vertices, lacks per-tet parents, disagrees with
// another part on a shared vertex's value, or leaves an owned tet without children.
absl::StatusOr<MergedIteration> MergeOwnedChildren(const WholeMesh& before,
                                                   const std::vector<HaloPart>& parts,
                                                   const std::vector<const RefineResult*>& results,
                                                   int iteration, bool best_tilings = false);

}  // namespace tetrefine::sharding
