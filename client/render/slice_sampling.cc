#include "client/render/slice_sampling.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "client/render/tet_locator.h"

namespace tetrefine::render {

std::vector<double> VertexValues(const Volume& volume, const Mesh& mesh) {
  if (!mesh.values.empty() && mesh.values.size() == mesh.points.size()) return mesh.values;
  std::vector<double> values(mesh.points.size());
  for (size_t i = 0; i < mesh.points.size(); ++i) {
    values[i] = volume.SampleIndex(volume.ClampToGrid(volume.ContinuousIndex(mesh.points[i])));
  }
  return values;
}

SliceSamples SampleSlice(const Volume& volume, const Mesh& mesh, const SlicePlane& plane,
                         double norm_coeff) {
  SliceSamples s;
  s.plane = plane;
  const size_t pixels = static_cast<size_t>(plane.width) * static_cast<size_t>(plane.height);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  s.trilinear.assign(pixels, nan);
  s.linear.assign(pixels, nan);
  s.discrepancy.assign(pixels, nan);
  const PlaneTetLocator locator(mesh, plane);
  double sum = 0.0;
  for (int row = 0; row < plane.height; ++row) {
    for (int column = 0; column < plane.width; ++column) {
      const size_t i = static_cast<size_t>(row) * plane.width + column;
      const Vec3 p = plane.PixelCentre(column, row);
      // Pixel centres lie inside the sampled box; clamping only absorbs the last bit of rounding.
      // An oblique grid's plane spans its world bounds, whose corners lie outside the rotated
      // grid: those pixels stay NaN (drawn as background) instead of repeating the boundary.
      const Vec3 u = volume.ContinuousIndex(p);
      if (volume.axis_aligned() || volume.Contains(u)) {
        s.trilinear[i] = volume.SampleIndex(volume.ClampToGrid(u));
      }
      const std::optional<PlaneTetLocator::Hit> hit = locator.Locate(p);
      if (!hit.has_value()) continue;
      const Tet& tet = mesh.tets[static_cast<size_t>(hit->tet)];
      double linear = 0.0;
      for (int c = 0; c < 4; ++c) linear += hit->weights[c] * mesh.values[tet[c]];
      s.linear[i] = linear;
      if (std::isnan(s.trilinear[i])) continue;  // a --clamp mesh outside an oblique grid
      s.discrepancy[i] = std::abs(s.trilinear[i] - linear) / norm_coeff;
      s.max_discrepancy = std::max(s.max_discrepancy, s.discrepancy[i]);
      sum += s.discrepancy[i];
      ++s.covered_pixels;
    }
  }
  if (s.covered_pixels > 0) s.mean_discrepancy = sum / static_cast<double>(s.covered_pixels);
  s.sections = PlaneSections(mesh, plane);
  return s;
}

}  // namespace tetrefine::render
