#pragma once

#include <cstdint>
#include <vector>

#include "absl/status/status.h"
#include "core/boundary_conformity.h"
#include "core/mesh.h"
#include "core/refine.h"
#include "core/volume.h"

namespace tetrefine {

// Checks a mesh before any work, in this order, and reports the first problem found, naming the
// field and index: finite coordinates within +-1e30; tet indices in range and distinct; no
// degenerate tet
// (|6V| <= 1e-12 L^3, L its longest edge); orientation (OrientationPolicy); every vertex inside
// the volume's sampled box unless OutsidePolicy::kClamp; no face in more than two tets and no
// two tets overlapping across a shared face; conformity of the boundary (CheckConformity): no
// hanging node, no boundary faces overlapping inside the mesh.
// *reoriented receives the number of inverted tets flipped. Under OrientationPolicy::kNormalize
// with at least one flipped, *tets receives the tets with inverted ones swapped; otherwise it is
// left empty, and the input's tets are the validated ones.
absl::Status ValidateMesh(const Mesh& mesh, const Volume& volume, OutsidePolicy outside,
                          OrientationPolicy orientation, std::vector<Tet>* tets,
                          int64_t* reoriented);

// Every coordinate finite and within +-1e30, beyond which a tet's 6V, its quality and the
// overlap check's face boxes overflow. InvalidArgument naming the first point that is not
// ("mesh.points[i] = (x, y, z) is too large ..." or "... is not finite").
absl::Status CheckCoordinates(const std::vector<Vec3>& points);

// The face check alone (no face in more than two tets, no overlap across a shared face). The
// tets must be positively oriented: which side of a face a tet lies on is read from the parity
// of its vertex order, not computed. When it passes and `boundary` is not null, *boundary
// receives every face of exactly one tet, once each, in an order that depends only on the tets.
absl::Status CheckFaces(const std::vector<Vec3>& points, const std::vector<Tet>& tets,
                        std::vector<BoundaryFace>* boundary = nullptr);

// The mesh checks that need no volume and hold for every valid input and every refinement
// output: CheckCoordinates, CheckFaces, then CheckBoundaryConformity on its boundary faces. Same
// preconditions as CheckFaces (positively oriented, non-degenerate tets with indices in range);
// points beyond +-1e30 are refused by CheckCoordinates rather than overflowing.
absl::Status CheckConformity(const std::vector<Vec3>& points, const std::vector<Tet>& tets);

}  // namespace tetrefine
