#pragma once

// Putting refined parts back together into one mesh.

#include <cstdint>
#include <vector>

#include "absl/status/statusor.h"
#include "core/mesh.h"
#include "core/refine.h"
#include "core/volume.h"
#include "sharding/mesh_partition.h"

namespace tetrefine::sharding {

// A refined mesh with its per-tet arrays: the merged whole, or one part of it kept as a piece.
struct RefinedMesh {
  Mesh mesh;
  std::vector<int32_t> tet_iteration;
  std::vector<float> tet_quality;
  std::vector<uint32_t> tet_parent;  // input tet of each tet, when the parts' results have it
};

// Merges the refined `results` of `parts` (one each, in part order) of `input`.
//
// Vertex order: the input's vertices keep their indices (as core Refine keeps them), then the new
// vertices part by part in each part's order; a vertex several parts created (a midpoint of an
// edge on a part boundary) is kept at its first occurrence. Parts are unified by the exact bits of
// the coordinates: a boundary midpoint is computed from the same two endpoints in every part that
// has the edge, so it has the same bits; Steiner points lie inside one tet and are never shared.
// Only new vertices inside another part's box are looked up, as only those can be shared.
// Tets (with their iteration, quality, label and input parent) follow part by part.
//
// Input vertices used by no tet are in no part: their values are sampled from `volume` here, the
// way the core samples them (`outside` says whether to clamp).
//
// INTERNAL if a part's result does not start with its input vertices, or if two parts disagree on
// the value at a shared vertex: either would mean the parts were not refined consistently.
absl::StatusOr<RefinedMesh> MergeParts(const Mesh& input, const Volume& volume,
                                       OutsidePolicy outside, const std::vector<MeshPart>& parts,
                                       const std::vector<const RefineResult*>& results);

// Part `p`'s refined result as a piece of the whole, without merging: its mesh and per-tet arrays
// moved out of `refined`, its tet parents mapped from the part's tets to the input's through
// part.input_tet. INTERNAL if a parent is not a tet of the part.
absl::StatusOr<RefinedMesh> PieceOfPart(int p, const MeshPart& part, RefineResult& refined);

}  // namespace tetrefine::sharding
