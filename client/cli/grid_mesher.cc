#include "client/cli/grid_mesher.h"

#include <array>
#include <limits>
#include <vector>

#include "absl/strings/str_cat.h"
#include "core/five_tet_cell.h"

namespace tetrefine::cli {
namespace {

// Sample indices of the cell boundaries along one axis.
std::vector<int64_t> AxisNodes(int64_t lo, int64_t hi, int64_t block) {
  std::vector<int64_t> nodes;
  for (int64_t i = lo; i < hi - 1; i += block) nodes.push_back(i);
  nodes.push_back(hi - 1);
  return nodes;
}

}  // namespace

absl::StatusOr<GridMesh> MeshVolumeGrid(const Volume& volume, const GridMeshOptions& options) {
  if (options.block < 1) {
    return absl::InvalidArgumentError(absl::StrCat("--block must be >= 1, got ", options.block));
  }
  const GridGeometry& grid = volume.grid();
  std::array<std::vector<int64_t>, 3> nodes;
  for (int a = 0; a < 3; ++a) nodes[a] = AxisNodes(volume.lo()[a], volume.hi()[a], options.block);
  const std::array<int64_t, 3> cells = {static_cast<int64_t>(nodes[0].size()) - 1,
                                        static_cast<int64_t>(nodes[1].size()) - 1,
                                        static_cast<int64_t>(nodes[2].size()) - 1};
  GridMesh out;
  out.cells = cells[0] * cells[1] * cells[2];
  if (out.cells > options.max_tets / 5) {
    return absl::InvalidArgumentError(absl::StrCat(
        cells[0], " x ", cells[1], " x ", cells[2], " cells at --block ", options.block, " make ",
        out.cells * 5, " tets, more than ", options.max_tets, "; use a larger --block"));
  }
  const int64_t nx = cells[0] + 1, ny = cells[1] + 1;
  const int64_t node_count = nx * ny * (cells[2] + 1);
  // Grid node -> mesh vertex, assigned on first use so unused nodes never become vertices.
  constexpr uint32_t kUnused = std::numeric_limits<uint32_t>::max();
  std::vector<uint32_t> vertex_of(static_cast<size_t>(node_count), kUnused);
  Mesh& mesh = out.mesh;
  auto vertex = [&](int64_t i, int64_t j, int64_t k) {
    const int64_t node = i + nx * (j + ny * k);
    uint32_t& v = vertex_of[static_cast<size_t>(node)];
    if (v == kUnused) {
      v = static_cast<uint32_t>(mesh.points.size());
      const Index3 s = {nodes[0][i], nodes[1][j], nodes[2][k]};
      // Through the grid's affine, so an oblique volume's mesh lies in its scanner frame.
      mesh.points.push_back(WorldOfIndex(
          grid, {static_cast<double>(s[0]), static_cast<double>(s[1]), static_cast<double>(s[2])}));
      mesh.values.push_back(volume.At(s[0], s[1], s[2]));
    }
    return v;
  };
  for (int64_t k = 0; k < cells[2]; ++k) {
    for (int64_t j = 0; j < cells[1]; ++j) {
      for (int64_t i = 0; i < cells[0]; ++i) {
        if (options.mask_threshold.has_value()) {
          bool inside = true;
          for (int b = 0; b < 8 && inside; ++b) {
            inside = volume.At(nodes[0][i + (b & 1)], nodes[1][j + ((b >> 1) & 1)],
                               nodes[2][k + ((b >> 2) & 1)]) >= *options.mask_threshold;
          }
          if (!inside) continue;
        }
        ++out.cells_kept;
        std::array<uint32_t, 8> corner;
        for (int b = 0; b < 8; ++b)
          corner[b] = vertex(i + (b & 1), j + ((b >> 1) & 1), k + (b >> 2));
        AppendFiveTetCell(corner, (i + j + k) % 2 == 0, mesh.points, &mesh.tets);
      }
    }
  }
  if (mesh.tets.empty()) {
    const std::array<double, 2> range = volume.ValueRange();
    return absl::InvalidArgumentError(absl::StrCat(
        "no cell has all 8 corner samples >= --mask-threshold ", *options.mask_threshold,
        " (the volume's values lie in [", range[0], ", ", range[1], "])"));
  }
  return out;
}

}  // namespace tetrefine::cli
