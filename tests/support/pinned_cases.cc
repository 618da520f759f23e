#include "tests/support/pinned_cases.h"

#include <cmath>
#include <utility>

#include "tests/support/geometry.h"
#include "tests/support/mesh_checks.h"

namespace tetrefine::testing {
namespace {

GridGeometry Grid() {
  GridGeometry g;
  g.dims = {24, 24, 12};
  g.spacing = {2.87, 2.87, 5.74};
  g.origin = {-10.0, 5.0, 1.0};
  return g;
}

Vec3 GridMax(const GridGeometry& g) {
  return {g.origin[0] + (g.dims[0] - 1) * g.spacing[0],
          g.origin[1] + (g.dims[1] - 1) * g.spacing[1],
          g.origin[2] + (g.dims[2] - 1) * g.spacing[2]};
}

Volume Blob(const Vec3& c, double width) {
  return AnalyticVolume(Grid(), [c, width](const Vec3& p) {
    const double d2 = (p[0] - c[0]) * (p[0] - c[0]) + (p[1] - c[1]) * (p[1] - c[1]) +
                      (p[2] - c[2]) * (p[2] - c[2]);
    return 100.0 * std::exp(-d2 / (width * width)) + 0.3 * p[0] - 0.2 * p[2];
  });
}

}  // namespace

std::vector<PinnedCase> PinnedCases() {
  const GridGeometry g = Grid();
  const Vec3 hi = GridMax(g);
  std::vector<PinnedCase> cases;
  cases.push_back({"sharp_blob_blocks", Blob({20.3, 37.1, 31.7}, 4.0),
                   FiveTetMesh(g.origin, hi, {6, 6, 3}), 0.05, 60});
  cases.push_back({"smooth_blob_blocks", Blob({20, 40, 30}, 9.0),
                   FiveTetMesh(g.origin, hi, {5, 5, 3}), 0.05, 16});
  Mesh cube = ReadMeditForTest(std::string(TETREFINE_SHARED_DATA_DIR) + "/unit_cube_1782tets.mesh");
  for (auto& p : cube.points) {
    for (int a = 0; a < 3; ++a) {
      const double lo = g.origin[a] + 1.5, span = hi[a] - 1.5 - lo;
      p[a] = lo + (p[a] + 0.5) * span;
    }
  }
  for (auto& t : cube.tets) {
    if (SignedVolume6(cube.points[t[0]], cube.points[t[1]], cube.points[t[2]], cube.points[t[3]]) <
        0) {
      std::swap(t[2], t[3]);
    }
  }
  cases.push_back({"cube_blob", Blob({15, 30, 25}, 5.0), std::move(cube), 0.05, 5});
  return cases;
}

}  // namespace tetrefine::testing
