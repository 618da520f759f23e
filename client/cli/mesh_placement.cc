#include "client/cli/mesh_placement.h"

#include <algorithm>

#include "absl/strings/str_cat.h"

namespace tetrefine::cli {

Box VolumeWorldBox(const Volume& volume) {
  const GridGeometry& g = volume.grid();
  Box box;
  for (int a = 0; a < 3; ++a) {
    box[0][a] = g.origin[a] + static_cast<double>(volume.lo()[a]) * g.spacing[a];
    box[1][a] = g.origin[a] + static_cast<double>(volume.hi()[a] - 1) * g.spacing[a];
  }
  return box;
}

std::string FormatBox(const Box& box) {
  return absl::StrCat("[", box[0][0], ", ", box[1][0], "] x [", box[0][1], ", ", box[1][1], "] x [",
                      box[0][2], ", ", box[1][2], "]");
}

int64_t FirstVertexOutside(const Volume& volume, const Mesh& mesh) {
  for (size_t i = 0; i < mesh.points.size(); ++i) {
    if (!volume.Contains(volume.ContinuousIndex(mesh.points[i]))) return static_cast<int64_t>(i);
  }
  return -1;
}

absl::Status FitMeshToVolume(const Volume& volume, Mesh* mesh) {
  if (mesh->points.empty()) return absl::OkStatus();
  Box from = {mesh->points[0], mesh->points[0]};
  for (const Vec3& p : mesh->points) {
    for (int a = 0; a < 3; ++a) {
      from[0][a] = std::min(from[0][a], p[a]);
      from[1][a] = std::max(from[1][a], p[a]);
    }
  }
  Box to = VolumeWorldBox(volume);
  const GridGeometry& g = volume.grid();
  for (int a = 0; a < 3; ++a) {
    const double extent = to[1][a] - to[0][a];
    const double margin = std::min(g.spacing[a], 0.25 * extent);
    to[0][a] += margin;
    to[1][a] -= margin;
    if (!(from[1][a] > from[0][a])) {
      return absl::InvalidArgumentError(absl::StrCat("the mesh is flat along axis ",
                                                     std::string(1, "xyz"[a]),
                                                     ", so it cannot be fitted to the volume"));
    }
  }
  for (Vec3& p : mesh->points) {
    for (int a = 0; a < 3; ++a) {
      const double t = (p[a] - from[0][a]) / (from[1][a] - from[0][a]);
      // The extremes map exactly onto the target box, whatever the rounding in between.
      p[a] = t <= 0.0 ? to[0][a] : t >= 1.0 ? to[1][a] : to[0][a] + t * (to[1][a] - to[0][a]);
    }
  }
  return absl::OkStatus();
}

}  // namespace tetrefine::cli
