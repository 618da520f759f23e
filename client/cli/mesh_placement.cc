#include "client/cli/mesh_placement.h"

#include <algorithm>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "client/io/axis_codes.h"

namespace tetrefine::cli {

namespace {

// The sampled index box [lo, hi - 1] of the volume.
Box IndexBox(const Volume& volume) {
  Box box;
  for (int a = 0; a < 3; ++a) {
    box[0][a] = static_cast<double>(volume.lo()[a]);
    box[1][a] = static_cast<double>(volume.hi()[a] - 1);
  }
  return box;
}

// The box of the vertices the tets use (all vertices when there is no tet). A vertex no tet uses
// (Gmsh's -save_all keeps geometry points) counted too, and squeezed the tets into a corner of
// the volume without a word (found by a file-format sweep). Out-of-range indices are left to
// the mesh's validation.
Box BoundingBox(const Mesh& mesh) {
  bool found = false;
  Box box{};
  const auto add = [&](const Vec3& p) {
    if (!found) box = {p, p};
    found = true;
    for (int a = 0; a < 3; ++a) {
      box[0][a] = std::min(box[0][a], p[a]);
      box[1][a] = std::max(box[1][a], p[a]);
    }
  };
  for (const Tet& t : mesh.tets) {
    for (uint32_t v : t) {
      if (v < mesh.points.size()) add(mesh.points[v]);
    }
  }
  if (!found) {
    for (const Vec3& p : mesh.points) add(p);
  }
  return box;
}

// Maps each point's coordinates linearly from box `from` onto box `to` (flipping axis a when
// flip[a]); the extremes land exactly on the target box, whatever the rounding in between.
void MapBox(const Box& from, const Box& to, const std::array<bool, 3>& flip,
            std::vector<Vec3>* points) {
  for (Vec3& p : *points) {
    for (int a = 0; a < 3; ++a) {
      double t = (p[a] - from[0][a]) / (from[1][a] - from[0][a]);
      if (flip[a]) t = 1.0 - t;
      p[a] = t <= 0.0 ? to[0][a] : t >= 1.0 ? to[1][a] : to[0][a] + t * (to[1][a] - to[0][a]);
    }
  }
}

}  // namespace

Box VolumeWorldBox(const Volume& volume) {
  const Box index = IndexBox(volume);
  return WorldBounds(volume.grid(), index[0], index[1]);
}

std::string FormatBox(const Box& box) {
  return absl::StrCat("[", box[0][0], ", ", box[1][0], "] x [", box[0][1], ", ", box[1][1], "] x [",
                      box[0][2], ", ", box[1][2], "]");
}

bool GridFillsItsWorldBox(const Volume& volume) {
  return volume.axis_aligned() || io::AxisCodesOf(volume.grid().direction).exact;
}

std::string WhereOutside(const Volume& volume, const Vec3& p) {
  const std::string at = absl::StrFormat("at (%g, %g, %g) mm", p[0], p[1], p[2]);
  if (GridFillsItsWorldBox(volume)) {
    return absl::StrCat(at, "; the volume spans ", FormatBox(VolumeWorldBox(volume)), " mm");
  }
  const Vec3 u = volume.ContinuousIndex(p);
  const Index3& d = volume.grid().dims;
  return absl::StrFormat(
      "%s, grid index (%g, %g, %g); the volume's oblique grid spans index [0, %d] x [0, %d] x "
      "[0, %d]",
      at, u[0], u[1], u[2], d[0] - 1, d[1] - 1, d[2] - 1);
}

int64_t FirstVertexOutside(const Volume& volume, const Mesh& mesh) {
  for (size_t i = 0; i < mesh.points.size(); ++i) {
    if (!volume.Contains(volume.ContinuousIndex(mesh.points[i]))) return static_cast<int64_t>(i);
  }
  return -1;
}

absl::Status FitMeshToVolume(const Volume& volume, Mesh* mesh) {
  if (mesh->points.empty()) return absl::OkStatus();
  const Box from = BoundingBox(*mesh);
  for (int a = 0; a < 3; ++a) {
    if (!(from[1][a] > from[0][a])) {
      return absl::InvalidArgumentError(absl::StrCat("the mesh is flat along axis ",
                                                     std::string(1, "xyz"[a]),
                                                     ", so it cannot be fitted to the volume"));
    }
  }
  const GridGeometry& g = volume.grid();
  if (volume.axis_aligned()) {
    Box to = VolumeWorldBox(volume);
    for (int a = 0; a < 3; ++a) {
      const double extent = to[1][a] - to[0][a];
      const double margin = std::min(g.spacing[a], 0.25 * extent);
      to[0][a] += margin;
      to[1][a] -= margin;
    }
    MapBox(from, to, {false, false, false}, &mesh->points);
    return absl::OkStatus();
  }
  // Oblique: fit into the index box (one sample of margin) and map through the grid's affine, so
  // the mesh lies inside the rotated parallelepiped. A direction that mirrors (det < 0) would
  // invert every tet; reversing index axis x as well keeps the orientation.
  Box to = IndexBox(volume);
  for (int a = 0; a < 3; ++a) {
    const double margin = std::min(1.0, 0.25 * (to[1][a] - to[0][a]));
    to[0][a] += margin;
    to[1][a] -= margin;
  }
  MapBox(from, to, {Determinant(g.direction) < 0.0, false, false}, &mesh->points);
  for (Vec3& p : mesh->points) p = WorldOfIndex(g, p);
  return absl::OkStatus();
}

}  // namespace tetrefine::cli
