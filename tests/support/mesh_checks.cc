#include "tests/support/mesh_checks.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>
#include <vector>

#include "core/mesh_validation.h"

namespace tetrefine::testing {

MeshMeasure Measure(const Mesh& m) {
  MeshMeasure out;
  // Faces as sorted vertex triples, sorted: a face met once is on the boundary. (A std::map
  // here was a fifth of the real-data tests' time, more under the sanitizers.)
  std::vector<std::array<uint32_t, 3>> faces;
  faces.reserve(4 * m.tets.size());
  for (const Tet& t : m.tets) {
    out.volume +=
        SignedVolume6(m.points[t[0]], m.points[t[1]], m.points[t[2]], m.points[t[3]]) / 6.0;
    for (int skip = 0; skip < 4; ++skip) {
      std::array<uint32_t, 3> f{};
      int k = 0;
      for (int i = 0; i < 4; ++i) {
        if (i != skip) f[k++] = t[i];
      }
      std::sort(f.begin(), f.end());
      faces.push_back(f);
    }
  }
  std::sort(faces.begin(), faces.end());
  for (size_t first = 0; first < faces.size();) {
    size_t end = first + 1;
    while (end < faces.size() && faces[end] == faces[first]) ++end;
    if (end - first == 1) {
      const auto& s = faces[first];
      const Vec3& a = m.points[s[0]];
      const Vec3& b = m.points[s[1]];
      const Vec3& c = m.points[s[2]];
      const Vec3 u = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
      const Vec3 v = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
      const Vec3 n = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2],
                      u[0] * v[1] - u[1] * v[0]};
      out.boundary_area += 0.5 * std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    }
    first = end;
  }
  return out;
}

std::string ConformityProblem(const Mesh& in, const Mesh& out) {
  for (size_t t = 0; t < out.tets.size(); ++t) {
    const Tet& q = out.tets[t];
    for (uint32_t i : q) {
      if (i >= out.points.size()) return "tet " + std::to_string(t) + " index out of range";
    }
    if (SignedVolume6(out.points[q[0]], out.points[q[1]], out.points[q[2]], out.points[q[3]]) <=
        0.0) {
      return "tet " + std::to_string(t) + " is not positively oriented";
    }
  }
  if (absl::Status s = CheckConformity(out.points, out.tets); !s.ok()) {
    return std::string(s.message());
  }
  std::vector<Vec3> sorted = out.points;
  std::sort(sorted.begin(), sorted.end());
  if (std::adjacent_find(sorted.begin(), sorted.end()) != sorted.end()) {
    return "two vertices share a position";
  }
  const MeshMeasure a = Measure(in), b = Measure(out);
  if (std::abs(a.volume - b.volume) > 1e-9 * std::abs(a.volume)) {
    return "volume changed from " + std::to_string(a.volume) + " to " + std::to_string(b.volume);
  }
  if (std::abs(a.boundary_area - b.boundary_area) > 1e-9 * a.boundary_area) {
    return "boundary area changed from " + std::to_string(a.boundary_area) + " to " +
           std::to_string(b.boundary_area);
  }
  return "";
}

Mesh ReadMeditForTest(const std::string& path) {
  std::ifstream in(path);
  Mesh m;
  std::string word;
  while (in >> word) {
    if (word == "Vertices") {
      size_t n;
      in >> n;
      m.points.resize(n);
      int ref;
      for (auto& p : m.points) in >> p[0] >> p[1] >> p[2] >> ref;
    } else if (word == "Tetrahedra") {
      size_t n;
      in >> n;
      m.tets.resize(n);
      int ref;
      for (auto& t : m.tets) {
        in >> t[0] >> t[1] >> t[2] >> t[3] >> ref;
        for (auto& i : t) --i;
      }
    }
  }
  return m;
}

std::vector<std::array<Vec3, 4>> GeometricTets(const Mesh& m) {
  std::vector<std::array<Vec3, 4>> out;
  for (const Tet& t : m.tets) {
    std::array<Vec3, 4> q = {m.points[t[0]], m.points[t[1]], m.points[t[2]], m.points[t[3]]};
    std::sort(q.begin(), q.end());
    out.push_back(q);
  }
  std::sort(out.begin(), out.end());
  return out;
}

}  // namespace tetrefine::testing
