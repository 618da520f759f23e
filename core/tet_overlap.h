#pragma once

// Check 5 of CheckBoundaryConformity: no tet that owns a boundary face overlaps another tet.
//
// Why that finds every overlap: a mesh whose tets are all positive and whose interior faces are
// each shared by two tets from opposite sides (what CheckFaces ensures) covers a point as many
// times as the boundary surface winds around it, and that count changes only across boundary
// faces. Where tets overlap, the count reaches some maximum k >= 2 on a region bounded by
// boundary faces, and on at least one of them the count drops from k to k - 1 going out, so
// that face's own tet lies on the region's side: right inside the face it shares points with
// at least k - 1 >= 1 other tets. So testing the owners of boundary faces against every tet
// finds an overlap whenever there is one, whatever its shape (two sides of a non-planar region
// triangulated differently, a mesh nested inside another, a flap folded back into the mesh),
// and tets far from the boundary are never tested against each other.

#include <atomic>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "absl/status/status.h"
#include "core/boundary_conformity.h"
#include "core/mesh.h"

namespace tetrefine {

// A boundary face and the one tet it is a face of.
struct OwnedFace {
  BoundaryFace face{};  // ascending ids
  int64_t tet = 0;
};

// Overlap depth of two tets' interiors: the smallest, over the 44 candidate separating axes of
// two tets (the 8 face normals, the 36 cross products of an edge of each), of how far their
// projections overlap, in the points' unit. At most `slack` of a pair's size is taken for
// contact: an axis along which they overlap by no more than
//   slack = 1e-10 L + 8 eps M + the rounding of the axis itself
// (L the pair's longest edge, M its largest coordinate magnitude, eps the double epsilon)
// separates them. Returns 0 when some axis separates them (touching, sharing a vertex, an edge
// or a face from opposite sides, or apart), else the depth (> 0): their interiors intersect.
// By the separating axis theorem for convex polyhedra these axes are the only ones to test.
double TetOverlapDepth(const std::array<Vec3, 4>& a, const std::array<Vec3, 4>& b);

// Errors: InvalidArgument "mesh is not conformal: mesh.tets[i] and mesh.tets[j] overlap ...",
// for the pair (i < j) that is smallest in index order, naming the boundary face it was found
// at and the depth. `faces` lists every boundary face with its tet, in an order that does not
// depend on the thread count.
// Which pairs are tested: by the argument above, some tet's closure holds a patch of the
// witnessing face of positive area with its interior on the face's own side. So only tets whose
// box meets a boundary face's box are looked at (a uniform grid over the faces passes over the
// rest on a few lookups), and of those only the ones that cross the face's plane, or lie on its
// inner side with a face in it, are tested against the face's tet; the neighbours of a convex
// boundary, which touch its planes from inside at a corner or an edge, are not.
// Cost: about linear in the mesh (about 100-160 ms for 1.08 M tets at 1 thread, where the face
// check takes 135 ms): a uniform grid over the faces' boxes, or a box tree where the face sizes
// spread over more than a factor 16 (tet_overlap.cc has the figures); parallel; the verdict and
// message do not depend on the thread count. The worst case is quadratic (many long faces and
// tets whose boxes all meet), as any box test's is.
absl::Status CheckNoOverlappingTets(const std::vector<Vec3>& points, const std::vector<Tet>& tets,
                                    const std::vector<OwnedFace>& faces);

// The bound of the geometric checks' candidate pairs (a tet or a boundary vertex against the
// boundary faces near it): tens per item on meshes of volumes, quadratic on valid meshes whose
// thin elements all meet near each other (thousands of slivers around one edge), which would let
// one request hold a core for minutes. A check refuses the mesh past kCrowdedPairFloor +
// kMaxCrowdedPairsPerItem x its items.
inline constexpr int64_t kMaxCrowdedPairsPerItem = 256;
inline constexpr int64_t kCrowdedPairFloor = int64_t{1} << 24;

// The count a check keeps against that bound, shared by its parallel blocks. Whether the total
// passes the bound does not depend on the thread count: a block stops early only once the sum,
// which only grows, is past it.
class CrowdedPairBudget {
 public:
  explicit CrowdedPairBudget(int64_t items)
      : max_(kCrowdedPairFloor + kMaxCrowdedPairsPerItem * items) {}
  // Moves a block's `pending` pairs to the total once there are 4096 of them; false when the
  // total is past the bound (the block may stop).
  bool Flush(int64_t& pending) {
    return pending < 4096 || total_.fetch_add(std::exchange(pending, 0)) <= max_;
  }
  // A block's last pairs.
  void Finish(int64_t pending) { total_.fetch_add(pending); }
  bool Exceeded() const { return total_.load() > max_; }
  int64_t max() const { return max_; }

 private:
  const int64_t max_;
  std::atomic<int64_t> total_{0};
};

// InvalidArgument: the mesh is too crowded for a check to run in bounded time: more than
// `max_pairs` pairs (each a `pair`, e.g. "tet and a boundary face meet within their bounding
// boxes"), naming the edge shared by the most tets (ties: smallest ids).
absl::Status CrowdedMeshError(const std::vector<Tet>& tets, const std::string& pair,
                              int64_t max_pairs);

}  // namespace tetrefine
