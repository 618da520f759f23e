#pragma once

#include "core/mesh.h"
#include "core/volume.h"

namespace tetrefine::reproduce {

// A left-ventricle perfusion phantom standing in for the paper's heart SPECT data (not available):
// a thick ellipsoidal shell (outer semi-axes 30, 30, 45 mm; inner surface at 0.62 of the outer),
// open at the base, its long axis tilted 35 degrees about x and 25 degrees about z, centred at the
// world origin. Counts follow a raised-cosine profile across the wall, wider than the wall as a
// SPECT point-spread function would make it, times a smooth regional pattern (+-10%) with a cold
// defect (-65% at its centre) on the inferior wall; a faint liver-like blob sits below the heart.
// Point samples, no noise. Values are counts in [0, ~100].
double HeartPhantomValue(const Vec3& p);

// The paper's Table 2 grids, centred on the phantom: heart1 64x64x24 voxels of
// 2.87x2.87x5.74 mm, heart2 32x32x11 voxels of 10.776 mm.
GridGeometry Heart1Grid();
GridGeometry Heart2Grid();

// The mesh between the inner and outer surfaces, as the paper meshed the ventricle between its
// reconstructed surfaces: world-space cells of `cell_mm` (5 tets each, conformal) whose centroid
// lies in the wall below the base plane, and whose corners all lie in the box [lo, hi] (the
// grids' common box, so that one mesh serves both). The surfaces come out as staircases of cells.
Mesh HeartShellMesh(double cell_mm, const Vec3& lo, const Vec3& hi);

// The Marschner-Lobb test signal (f_M = 6, alpha = 0.25) on [-1, 1]^3, values in [0, 1].
double MarschnerLobbValue(const Vec3& p);

// n^3 samples spanning [-1, 1]^3 (the classic grid is 41^3).
GridGeometry MarschnerLobbGrid(int n);

}  // namespace tetrefine::reproduce
