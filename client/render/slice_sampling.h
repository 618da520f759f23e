#pragma once

#include <cstdint>
#include <vector>

#include "client/render/plane_section.h"
#include "client/render/slice_plane.h"
#include "core/mesh.h"
#include "core/volume.h"

namespace tetrefine::render {

// What a figure shows of one mesh on one plane, per pixel of plane.width x plane.height, row 0
// at the top, index row * width + column, sampled at the pixel centres:
//   trilinear:   the volume's trilinear value (paper eq. 1), volume value units; NaN outside an
//                oblique grid (its plane spans the rotated grid's world bounds);
//   linear:      the mesh's linear interpolation of its vertex values, NaN where no tet
//                contains the pixel centre;
//   discrepancy: |trilinear - linear| / norm_coeff (paper eq. 3), NaN where either is.
// sections: the tet-plane intersection polygons, whose sides are the mesh's edges on the plane.
struct SliceSamples {
  SlicePlane plane;
  std::vector<double> trilinear;
  std::vector<double> linear;
  std::vector<double> discrepancy;
  std::vector<TetSection> sections;
  int64_t covered_pixels = 0;     // pixels with a discrepancy (both values)
  double max_discrepancy = 0.0;   // over covered pixels
  double mean_discrepancy = 0.0;  // over covered pixels
};

// The mesh's vertex values: its own `values` when it has them (one per vertex), otherwise the
// volume sampled at each vertex (clamped to the grid's box for vertices outside it), as
// refinement samples them.
std::vector<double> VertexValues(const Volume& volume, const Mesh& mesh);

// Samples `plane` of `volume` and of `mesh`, whose values must be set (one per vertex, e.g.
// VertexValues). norm_coeff > 0 (usually the volume's max - min).
SliceSamples SampleSlice(const Volume& volume, const Mesh& mesh, const SlicePlane& plane,
                         double norm_coeff);

}  // namespace tetrefine::render
