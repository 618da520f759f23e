#pragma once

#include <array>
#include <cstdint>

#include "absl/status/status.h"
#include "core/mesh.h"

namespace tetrefine::cli {

// Geometry and validity of a tet mesh on its own (no volume), for `verify` and `info`.
struct MeshReport {
  int64_t vertices = 0;
  int64_t tets = 0;
  std::array<Vec3, 2> bounding_box{};  // min and max corner; zero for an empty mesh

  // |6V| <= 1e-12 L^3 (L the longest edge): the same rule as the core's validation.
  int64_t degenerate_tets = 0;
  int64_t first_degenerate = -1;
  int64_t inverted_tets = 0;  // negative volume, not degenerate
  int64_t first_inverted = -1;
  // Used vertices (some tet has them) with the coordinates of an earlier used vertex.
  int64_t duplicate_vertices = 0;
  std::array<int64_t, 2> first_duplicate = {-1, -1};
  int64_t unused_vertices = 0;
  // core CheckConformity (the face check, then no hanging node and a closed boundary) on the tets
  // with inverted ones flipped, so a face shared by three tets is reported whatever the
  // orientation: OK, or the first problem. With degenerate tets, only CheckFaces, on the others.
  absl::Status faces;

  double volume = 0.0;         // sum of |V|
  double boundary_area = 0.0;  // area of the faces that belong to exactly one tet
  int64_t boundary_faces = 0;
  double quality_min = 0.0;  // mean ratio (Liu and Joe), over all tets
  double quality_mean = 0.0;

  bool valid() const {
    return degenerate_tets == 0 && inverted_tets == 0 && duplicate_vertices == 0 && faces.ok();
  }
};

MeshReport AnalyzeMesh(const Mesh& mesh);

}  // namespace tetrefine::cli
