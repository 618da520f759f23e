#include "tools/reproduce/uniform_refine.h"

#include <array>
#include <cstdint>
#include <utility>

#include "absl/container/flat_hash_map.h"
#include "core/subdivision_table.h"
#include "core/tet_topology.h"

namespace tetrefine::reproduce {

void SampleValues(const Volume& volume, Mesh& mesh) {
  mesh.values.resize(mesh.points.size());
  for (size_t i = 0; i < mesh.points.size(); ++i) {
    mesh.values[i] = volume.SampleIndex(volume.ClampToGrid(volume.ContinuousIndex(mesh.points[i])));
  }
}

Mesh UniformRefine(const Volume& volume, const Mesh& mesh) {
  constexpr uint32_t kAllEdges = 63;
  const auto& table = SubdivisionTable();
  Mesh out;
  out.points = mesh.points;
  out.values = mesh.values;
  out.tets.reserve(mesh.tets.size() * 8);
  absl::flat_hash_map<uint64_t, uint32_t> midpoint;
  midpoint.reserve(mesh.tets.size() * 2);
  for (const Tet& t : mesh.tets) {
    std::array<uint32_t, kNumLocalPoints> id{};
    std::array<Vec3, 10> p;
    for (int c = 0; c < 4; ++c) {
      id[c] = t[c];
      p[c] = mesh.points[t[c]];
    }
    for (int e = 0; e < 6; ++e) {
      const int a = kTetEdges[e][0], b = kTetEdges[e][1];
      for (int x = 0; x < 3; ++x) p[4 + e][x] = 0.5 * (p[a][x] + p[b][x]);
      const uint32_t lo = std::min(t[a], t[b]), hi = std::max(t[a], t[b]);
      const auto [it, inserted] =
          midpoint.try_emplace(uint64_t{lo} << 32 | hi, static_cast<uint32_t>(out.points.size()));
      if (inserted) {
        out.points.push_back(p[4 + e]);
        out.values.push_back(
            volume.SampleIndex(volume.ClampToGrid(volume.ContinuousIndex(p[4 + e]))));
      }
      id[4 + e] = it->second;
    }
    const SubdivisionEntry& entry = table[SubdivisionKey(kAllEdges, p)];
    for (int c = 0; c < entry.tet_count; ++c) {
      const auto& l = entry.tets[c];
      out.tets.push_back({id[l[0]], id[l[1]], id[l[2]], id[l[3]]});
    }
  }
  return out;
}

}  // namespace tetrefine::reproduce
