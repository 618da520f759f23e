#include "client/cli/mesh_report.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <vector>

#include "core/mesh_validation.h"
#include "core/quality.h"

namespace tetrefine::cli {
namespace {

double Length2(const Vec3& a, const Vec3& b) {
  const double x = a[0] - b[0], y = a[1] - b[1], z = a[2] - b[2];
  return x * x + y * y + z * z;
}

double TriangleArea(const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 u = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
  const Vec3 v = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
  const Vec3 n = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
  return 0.5 * std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
}

// Among the vertices some tet uses: two used vertices at one position are a crack (or two
// meshes glued without merging), while an unused copy is inert. refine carries unused vertices
// through to its output unchanged, so counting them made verify refuse refine's own result for
// an input it had accepted (found by a CLI sweep).
void CountDuplicates(const Mesh& mesh, const std::vector<bool>& used, MeshReport* report) {
  std::vector<uint32_t> order;
  order.reserve(mesh.points.size());
  for (uint32_t v = 0; v < mesh.points.size(); ++v) {
    if (used[v]) order.push_back(v);
  }
  std::sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) {
    return mesh.points[a] != mesh.points[b] ? mesh.points[a] < mesh.points[b] : a < b;
  });
  for (size_t i = 1; i < order.size(); ++i) {
    if (mesh.points[order[i]] != mesh.points[order[i - 1]]) continue;
    if (report->duplicate_vertices == 0) {
      // order[] is sorted by index within equal points, so order[i - 1] is the earlier vertex.
      report->first_duplicate = {order[i - 1], order[i]};
    }
    ++report->duplicate_vertices;
  }
}

void MeasureBoundary(const Mesh& mesh, MeshReport* report) {
  struct Face {
    std::array<uint32_t, 3> v;
    bool operator<(const Face& o) const { return v < o.v; }
    bool operator==(const Face& o) const { return v == o.v; }
  };
  std::vector<Face> faces;
  faces.reserve(mesh.tets.size() * 4);
  for (const Tet& t : mesh.tets) {
    for (int skip = 0; skip < 4; ++skip) {
      Face f;
      int n = 0;
      for (int c = 0; c < 4; ++c) {
        if (c != skip) f.v[n++] = t[c];
      }
      std::sort(f.v.begin(), f.v.end());
      faces.push_back(f);
    }
  }
  std::sort(faces.begin(), faces.end());
  for (size_t i = 0; i < faces.size();) {
    size_t j = i + 1;
    while (j < faces.size() && faces[j] == faces[i]) ++j;
    if (j - i == 1) {
      ++report->boundary_faces;
      report->boundary_area += TriangleArea(mesh.points[faces[i].v[0]], mesh.points[faces[i].v[1]],
                                            mesh.points[faces[i].v[2]]);
    }
    i = j;
  }
}

}  // namespace

MeshReport AnalyzeMesh(const Mesh& mesh) {
  MeshReport report;
  report.vertices = static_cast<int64_t>(mesh.points.size());
  report.tets = static_cast<int64_t>(mesh.tets.size());
  if (!mesh.points.empty()) {
    report.bounding_box = {mesh.points[0], mesh.points[0]};
    for (const Vec3& p : mesh.points) {
      for (int a = 0; a < 3; ++a) {
        report.bounding_box[0][a] = std::min(report.bounding_box[0][a], p[a]);
        report.bounding_box[1][a] = std::max(report.bounding_box[1][a], p[a]);
      }
    }
  }
  std::vector<bool> used(mesh.points.size(), false);
  std::vector<Tet> oriented;
  oriented.reserve(mesh.tets.size());
  double quality_sum = 0.0;
  report.quality_min = mesh.tets.empty() ? 0.0 : std::numeric_limits<double>::infinity();
  for (size_t t = 0; t < mesh.tets.size(); ++t) {
    Tet tet = mesh.tets[t];
    const Vec3 &a = mesh.points[tet[0]], &b = mesh.points[tet[1]], &c = mesh.points[tet[2]],
               &d = mesh.points[tet[3]];
    for (uint32_t v : tet) used[v] = true;
    const double v6 = SignedVolume6(a, b, c, d);
    const double l2 = std::max(
        {Length2(a, b), Length2(a, c), Length2(a, d), Length2(b, c), Length2(b, d), Length2(c, d)});
    const double quality = MeanRatio(a, b, c, d);
    quality_sum += quality;
    report.quality_min = std::min(report.quality_min, quality);
    report.volume += std::abs(v6) / 6.0;
    if (std::abs(v6) <= 1e-12 * l2 * std::sqrt(l2)) {
      if (report.degenerate_tets++ == 0) report.first_degenerate = static_cast<int64_t>(t);
      continue;
    }
    if (v6 < 0.0) {
      if (report.inverted_tets++ == 0) report.first_inverted = static_cast<int64_t>(t);
      std::swap(tet[2], tet[3]);
    }
    oriented.push_back(tet);
  }
  if (!mesh.tets.empty()) quality_sum /= static_cast<double>(mesh.tets.size());
  report.quality_mean = quality_sum;
  report.unused_vertices = std::count(used.begin(), used.end(), false);
  CountDuplicates(mesh, used, &report);
  // With degenerate tets left out their neighbours' faces would look like boundary, and the
  // conformity check would report what is really the degenerate tets, already reported.
  // Coordinates beyond +-1e30 overflow the face checks' geometry: they are the finding
  // (CheckConformity checks them itself).
  if (report.degenerate_tets > 0) {
    report.faces = CheckCoordinates(mesh.points);
    if (report.faces.ok()) report.faces = CheckFaces(mesh.points, oriented);
  } else {
    report.faces = CheckConformity(mesh.points, oriented);
  }
  MeasureBoundary(mesh, &report);
  return report;
}

}  // namespace tetrefine::cli
