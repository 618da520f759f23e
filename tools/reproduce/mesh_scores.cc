#include "tools/reproduce/mesh_scores.h"

#include <algorithm>
#include <cmath>

#include "core/edge_table.h"

namespace tetrefine::reproduce {

QualityStats MeshQuality(const Mesh& mesh) {
  QualityStats q;
  q.min = 1.0;
  double sum = 0.0;
  for (const Tet& t : mesh.tets) {
    const double eta =
        MeanRatio(mesh.points[t[0]], mesh.points[t[1]], mesh.points[t[2]], mesh.points[t[3]]);
    q.min = std::min(q.min, eta);
    sum += eta;
  }
  q.count = static_cast<int64_t>(mesh.tets.size());
  q.mean = mesh.tets.empty() ? 0.0 : sum / static_cast<double>(q.count);
  if (mesh.tets.empty()) q.min = 0.0;
  return q;
}

MidpointErrorStats MidpointErrors(const Volume& volume, const Mesh& mesh, double norm_coeff) {
  const EdgeTable edges = BuildEdgeTable(mesh.tets, static_cast<int64_t>(mesh.points.size()));
  MidpointErrorStats out;
  out.edges = edges.size();
  double sum = 0.0;
  for (size_t v = 0; v + 1 < edges.first.size(); ++v) {
    for (uint32_t e = edges.first[v]; e < edges.first[v + 1]; ++e) {
      const uint32_t w = edges.second[e];
      const Vec3& a = mesh.points[v];
      const Vec3& b = mesh.points[w];
      const Vec3 mid{0.5 * (a[0] + b[0]), 0.5 * (a[1] + b[1]), 0.5 * (a[2] + b[2])};
      const double real = volume.SampleIndex(volume.ClampToGrid(volume.ContinuousIndex(mid)));
      const double error = std::abs(real - 0.5 * (mesh.values[v] + mesh.values[w])) / norm_coeff;
      out.max_error = std::max(out.max_error, error);
      sum += error;
    }
  }
  if (out.edges > 0) out.mean_error = sum / static_cast<double>(out.edges);
  return out;
}

}  // namespace tetrefine::reproduce
