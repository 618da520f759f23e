#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "absl/status/status.h"
#include "core/mesh.h"

namespace tetrefine {

// A face that belongs to exactly one tet: its three vertex ids, ascending.
using BoundaryFace = std::array<uint32_t, 3>;

// The checks that a face check cannot make, on a mesh that passed it (CheckFaces, which also
// lists `boundary`: every face of exactly one of `tets`, each once). A hanging node (a vertex
// inside another tet's edge or face) leaves faces of exactly one tet inside the mesh, which the
// face check takes for boundary, and tets may overlap. In this order, reporting the first
// problem found:
//   1. No boundary vertex lies on a boundary face it is not a vertex of, within
//      1e-13 L + 8 eps M of the closed triangle (L the face's longest edge, M the largest
//      coordinate magnitude of its vertices, eps the double epsilon: how far rounding puts a
//      midpoint off its edge). Covers a vertex in a face, on an edge or at a corner (two
//      coincident vertices with different ids, e.g. two cubes touching with duplicated
//      vertices, or a crack). The opposite vertex of the face's own tet never counts: a sliver
//      close to its boundary face is a valid tet. Reports the smallest such vertex and, among
//      its faces, the smallest face.
//   2. The boundary is closed: every edge of the boundary faces is used by an even number of
//      them (a hanging node on an edge leaves that edge in one face on the unsplit side).
//      Reports the smallest such edge.
//   3. No two boundary faces on a common edge fold onto each other: lie in one plane (the
//      fourth vertex within the tolerance of 1. of the other face's plane) on the same side of
//      the edge. Two triangulations of one planar region disagree on some edge of its outline
//      exactly like this, so it finds a square face split by crossing diagonals on its two
//      sides, which leaves no hanging vertex and an even count on every edge. Pairs that are
//      two faces of one (sliver) tet do not count. Reports the smallest (edge, third vertices).
//   4. No two tets overlap across a quadrilateral that is not planar and is split differently
//      on its two sides. Its four triangles are boundary faces that close around a tet the mesh
//      does not have; where the two sides bulge into each other, a face's own tet lies on the
//      inside of that shell with its fourth vertex outside it (beyond 1e-12 L^3 in 6 x volume,
//      the degenerate-tet bound), reaching out through the shell. Where they bulge apart they
//      leave a tet-shaped cavity, and a shell may also hold its own tets (a lone tet split at an
//      inner point): both valid, both pass. Reports the smallest such shell.
//   5. No tet that owns a boundary face overlaps another tet (core/tet_overlap.h: the interiors
//      intersect by more than 1e-10 of the pair's size along every separating axis). Any
//      overlap at all shows at some boundary face's own tet (why is in that header), so this
//      catches what 3. and 4. name more precisely and the rest: regions larger than one
//      quadrilateral triangulated differently on their two sides, a mesh inside another, a
//      boundary folded back into the mesh. Reports the smallest pair of tets.
// Cost: O(T) to name a tet in a message, otherwise about linear in the boundary's size (a hash
// grid with one level per power of two of face size) for 1.-4., and for 5. a box tree over the
// boundary's tets queried once per tet; parallel, and the verdict and message do not depend on
// the thread count. `points` must be finite (ValidateMesh checks that first).
// Errors are InvalidArgument and start with "mesh is not conformal: ", naming the vertex or
// edge by its ids, the face by its vertex ids and the tet that owns it as mesh.tets[i].
absl::Status CheckBoundaryConformity(const std::vector<Vec3>& points, const std::vector<Tet>& tets,
                                     const std::vector<BoundaryFace>& boundary);

}  // namespace tetrefine
