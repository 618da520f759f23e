#include "sharding/mesh_partition.h"

#include <algorithm>
#include <limits>
#include <span>
#include <tuple>

namespace tetrefine::sharding {
namespace {

constexpr uint32_t kNone = std::numeric_limits<uint32_t>::max();

Vec3 Centroid(const Mesh& mesh, const Tet& t) {
  Vec3 c{0.0, 0.0, 0.0};
  for (int a = 0; a < 3; ++a) {
    c[a] = 0.25 * (mesh.points[t[0]][a] + mesh.points[t[1]][a] + mesh.points[t[2]][a] +
                   mesh.points[t[3]][a]);
  }
  return c;
}

void Bisect(std::span<uint32_t> ids, int parts, const std::vector<Vec3>& centroid,
            std::vector<std::vector<uint32_t>>& out) {
  if (parts == 1) {
    std::vector<uint32_t>& group = out.emplace_back(ids.begin(), ids.end());
    std::sort(group.begin(), group.end());
    return;
  }
  Vec3 lo = centroid[ids[0]], hi = centroid[ids[0]];
  for (uint32_t id : ids) {
    for (int a = 0; a < 3; ++a) {
      lo[a] = std::min(lo[a], centroid[id][a]);
      hi[a] = std::max(hi[a], centroid[id][a]);
    }
  }
  int axis = 0;
  for (int a = 1; a < 3; ++a) {
    if (hi[a] - lo[a] > hi[axis] - lo[axis]) axis = a;
  }
  const int left_parts = parts / 2;
  const size_t cut = ids.size() * static_cast<size_t>(left_parts) / static_cast<size_t>(parts);
  // A strict total order (coordinate, then index): which tets fall left of the cut does not
  // depend on how nth_element arranges them.
  std::nth_element(ids.begin(), ids.begin() + static_cast<std::ptrdiff_t>(cut), ids.end(),
                   [&](uint32_t a, uint32_t b) {
                     return std::tie(centroid[a][axis], a) < std::tie(centroid[b][axis], b);
                   });
  Bisect(ids.first(cut), left_parts, centroid, out);
  Bisect(ids.subspan(cut), parts - left_parts, centroid, out);
}

}  // namespace

bool InBox(const Vec3& p, const Vec3& lo, const Vec3& hi) {
  return p[0] >= lo[0] && p[0] <= hi[0] && p[1] >= lo[1] && p[1] <= hi[1] && p[2] >= lo[2] &&
         p[2] <= hi[2];
}

std::vector<std::vector<uint32_t>> PartitionTets(const Mesh& mesh, int parts) {
  const size_t n = mesh.tets.size();
  std::vector<std::vector<uint32_t>> out;
  if (n == 0) return out;
  parts = static_cast<int>(std::clamp<size_t>(static_cast<size_t>(std::max(parts, 1)), 1, n));
  std::vector<Vec3> centroid(n);
  std::vector<uint32_t> ids(n);
  for (size_t t = 0; t < n; ++t) {
    centroid[t] = Centroid(mesh, mesh.tets[t]);
    ids[t] = static_cast<uint32_t>(t);
  }
  out.reserve(static_cast<size_t>(parts));
  Bisect(ids, parts, centroid, out);
  return out;
}

std::vector<MeshPart> ExtractParts(const Mesh& mesh,
                                   const std::vector<std::vector<uint32_t>>& groups) {
  const bool has_values = !mesh.values.empty() && mesh.values.size() == mesh.points.size();
  const bool has_labels = !mesh.labels.empty() && mesh.labels.size() == mesh.tets.size();
  std::vector<uint32_t> local(mesh.points.size(), kNone);
  std::vector<MeshPart> parts(groups.size());
  for (size_t p = 0; p < groups.size(); ++p) {
    MeshPart& part = parts[p];
    for (uint32_t t : groups[p]) {
      for (uint32_t v : mesh.tets[t]) {
        if (local[v] == kNone) {
          local[v] = 0;
          part.input_vertex.push_back(v);
        }
      }
    }
    std::sort(part.input_vertex.begin(), part.input_vertex.end());
    part.mesh.points.reserve(part.input_vertex.size());
    for (size_t i = 0; i < part.input_vertex.size(); ++i) {
      const uint32_t v = part.input_vertex[i];
      local[v] = static_cast<uint32_t>(i);
      part.mesh.points.push_back(mesh.points[v]);
      if (has_values) part.mesh.values.push_back(mesh.values[v]);
    }
    part.mesh.tets.reserve(groups[p].size());
    for (uint32_t t : groups[p]) {
      const Tet& tet = mesh.tets[t];
      part.mesh.tets.push_back({local[tet[0]], local[tet[1]], local[tet[2]], local[tet[3]]});
      if (has_labels) part.mesh.labels.push_back(mesh.labels[t]);
    }
    part.input_tet = groups[p];
    if (!part.mesh.points.empty()) {
      part.box_lo = part.box_hi = part.mesh.points[0];
      for (const Vec3& q : part.mesh.points) {
        for (int a = 0; a < 3; ++a) {
          part.box_lo[a] = std::min(part.box_lo[a], q[a]);
          part.box_hi[a] = std::max(part.box_hi[a], q[a]);
        }
      }
    }
    for (uint32_t v : part.input_vertex) local[v] = kNone;
  }
  return parts;
}

}  // namespace tetrefine::sharding
