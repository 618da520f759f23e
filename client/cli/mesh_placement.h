#pragma once

#include <array>
#include <cstdint>
#include <string>

#include "absl/status/status.h"
#include "core/mesh.h"
#include "core/volume.h"

namespace tetrefine::cli {

using Box = std::array<Vec3, 2>;  // min and max corner, world units

// The world box spanned by the volume's samples (the box refinement may sample in); for an oblique
// volume the axis-aligned bounding box of the rotated sampled region.
Box VolumeWorldBox(const Volume& volume);

// "[-32, 32] x [-40, 40] x [-16, 32]".
std::string FormatBox(const Box& box);

// Index of the first vertex outside the volume's sampled box (with the core's tolerance), or -1.
int64_t FirstVertexOutside(const Volume& volume, const Mesh& mesh);

// True when the volume's grid fills its world bounding box: its axes are the world's, maybe
// flipped or swapped (most scanners' files), not rotated. Only then is a point inside the box
// inside the grid.
bool GridFillsItsWorldBox(const Volume& volume);

// Where world point `p`, outside the volume, is, for messages: "at (x, y, z) mm; the volume
// spans [..] x [..] x [..] mm", and for an oblique volume, whose world bounding box can hold
// points outside its grid, "at (x, y, z) mm, grid index (i, j, k); the volume's oblique grid
// spans index [0, nx - 1] x [0, ny - 1] x [0, nz - 1]" (an outside review found a vertex said
// to lie outside a box that held it).
std::string WhereOutside(const Volume& volume, const Vec3& p);

// --fit-mesh-to-volume: scales each axis and translates so that the bounding box of the vertices
// the tets use (all vertices without tets; an unused vertex outside it is clamped onto it) becomes
// the volume's world box shrunk by a margin of one voxel on every side (a quarter of the box when
// the volume is thinner than four voxels). Positive scales, so orientation is kept. For an oblique
// volume the box is the index box (one sample of margin) mapped through the grid's affine, with
// index x reversed when the direction mirrors, so the mesh lies inside and keeps orientation.
// Meant for
// meshes in their own unit frame, like examples/unit_cube_1782tets.mesh. Error: a mesh that is
// flat along an axis.
absl::Status FitMeshToVolume(const Volume& volume, Mesh* mesh);

}  // namespace tetrefine::cli
