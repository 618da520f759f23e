#pragma once

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <vector>

#include "absl/status/statusor.h"
#include "core/voxel_type.h"

namespace tetrefine {

using Vec3 = std::array<double, 3>;
using Index3 = std::array<int64_t, 3>;
// A 3x3 matrix, row-major: element (row, column) at [3 * row + column].
using Mat3 = std::array<double, 9>;

inline constexpr Mat3 kIdentityDirection{1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0};

// Geometry of a whole voxel grid: sample (i, j, k) sits at world position
// origin + direction * diag(spacing) * (i, j, k), in the caller's world unit (millimetres for
// imaging data). The identity direction is the axis-aligned grid; an oblique one (rotated,
// sheared or axis-permuted, common in MRI) keeps the samples in storage order, so a mesh in
// scanner coordinates lines up without resampling.
struct GridGeometry {
  Index3 dims{0, 0, 0};         // samples per axis, each >= 2 (trilinear needs a cell)
  Vec3 origin{0.0, 0.0, 0.0};   // world position of sample (0, 0, 0)
  Vec3 spacing{1.0, 1.0, 1.0};  // world distance between samples per axis, each > 0
  // Columns are the world directions of the index axes i, j, k (unit length by convention; the
  // length lives in spacing). Finite, with |det| >= kMinDirectionDeterminant.
  Mat3 direction = kIdentityDirection;
};

// Smallest |det(direction)| a grid accepts: below it the index axes are nearly parallel and the
// world-to-index map amplifies rounding beyond what sampling tolerates.
inline constexpr double kMinDirectionDeterminant = 1e-6;

// True when `direction` is exactly the identity (bit for bit, -0 counts as 0): the grid then
// uses the axis-aligned formulas that every pinned result was computed with.
bool IsIdentityDirection(const Mat3& direction);

// Determinant of a 3x3 row-major matrix.
double Determinant(const Mat3& m);

// What makes a direction matrix unusable, for callers that name their own field: the volume
// (core) and the wire's volume header check the same rule and must not drift apart.
struct DirectionDefect {
  enum class Kind : uint8_t {
    kNone,        // usable
    kNotFinite,   // entry `index` (row-major) is NaN or infinite
    kZeroColumn,  // column `index` has zero length, or its length overflows
    kSingular,    // |det| of the unit-column matrix (`det`) is below kMinDirectionDeterminant
  };
  Kind kind = Kind::kNone;
  int index = 0;
  double det = 0.0;
};

// The first defect of `direction` in the order above. Scale-free: the determinant is taken of
// the columns normalised to unit length, so a direction given with lengths (a raw affine) is
// judged by its angles alone.
DirectionDefect FindDirectionDefect(const Mat3& direction);

// World position of continuous index u: origin + direction * (spacing * u). For the identity
// direction exactly origin + spacing * u per axis (the axis-aligned formula).
Vec3 WorldOfIndex(const GridGeometry& grid, const Vec3& u);

// The world positions of the 8 corners of the index box [lo, hi] (inclusive continuous
// indices), ordered x fastest. For an axis-aligned grid they span the box's world extent.
std::array<Vec3, 8> WorldCorners(const GridGeometry& grid, const Vec3& lo, const Vec3& hi);

// The axis-aligned world bounding box [min, max] of the index box [lo, hi].
std::array<Vec3, 2> WorldBounds(const GridGeometry& grid, const Vec3& lo, const Vec3& hi);

// World point to continuous grid index (Volume::ContinuousIndex), by value so that a loop over
// many points keeps it in registers: a Volume's doubles could alias the loop's output arrays.
struct IndexMap {
  Vec3 origin;          // the grid's origin
  Vec3 spacing;         // the grid's spacing
  Mat3 world_to_index;  // (direction * diag(spacing))^-1; unused when kAxisAligned
  // kAxisAligned must be Volume::axis_aligned(): (p - origin) / spacing per axis for the
  // identity direction (kept verbatim so axis-aligned results stay bit-identical), otherwise
  // world_to_index * (p - origin), each row summed left to right.
  template <bool kAxisAligned>
  Vec3 Apply(const Vec3& p) const {
    if constexpr (kAxisAligned) {
      return {(p[0] - origin[0]) / spacing[0], (p[1] - origin[1]) / spacing[1],
              (p[2] - origin[2]) / spacing[2]};
    } else {
      const double d[3] = {p[0] - origin[0], p[1] - origin[1], p[2] - origin[2]};
      const Mat3& m = world_to_index;
      return {m[0] * d[0] + m[1] * d[1] + m[2] * d[2], m[3] * d[0] + m[4] * d[1] + m[5] * d[2],
              m[6] * d[0] + m[7] * d[1] + m[8] * d[2]};
    }
  }
};

namespace volume_internal {

// The voxel at `index` of little-endian `base`, read as T.
template <typename T>
double Load(const std::byte* base, int64_t index) {
  T value;
  std::memcpy(&value, base + index * static_cast<int64_t>(sizeof(T)), sizeof(T));
  return static_cast<double>(value);
}

inline double Lerp(double a, double b, double t) { return a * (1.0 - t) + b * t; }

}  // namespace volume_internal

// Trilinear sampling of a volume (Volume::SampleIndex) with the voxel type as a template
// argument and everything it reads by value: a loop over many points then switches on the type
// once and keeps the slab's bounds in registers. Volume::SampleIndex is this, so both give the
// same bits by construction.
struct TrilinearSampler {
  const std::byte* data;  // the slab's samples, x fastest
  Vec3 max_index;         // grid dims - 1 per axis: the grid's box is [0, max_index]
  Index3 lo;              // the slab's first sample per axis
  Index3 max_cell;        // hi - 2 per axis: the slab's last cell
  int64_t dy, dz;         // samples between y and z neighbours in data

  // The trilinear value at continuous index u (see Volume::SampleIndex). T must be the C++ type
  // of the volume's VoxelType (uint8_t, int16_t, uint16_t, int32_t, float, double).
  template <typename T>
  double Sample(const Vec3& u) const {
    using volume_internal::Lerp;
    using volume_internal::Load;
    int64_t cell[3];
    double t[3];
    for (int a = 0; a < 3; ++a) {
      // Clamped to the grid first (a vertex within tolerance outside samples the boundary), then
      // the cell clamped into the slab: on a cell face either neighbour gives the same bits.
      const double x = std::clamp(u[a], 0.0, max_index[a]);
      // x >= 0 here, so truncation is floor (and needs no libm call on baseline x86-64).
      const int64_t c = static_cast<int64_t>(x);
      cell[a] = std::clamp(c, lo[a], max_cell[a]);
      t[a] = x - static_cast<double>(cell[a]);
    }
    const int64_t base = (cell[0] - lo[0]) + dy * (cell[1] - lo[1]) + dz * (cell[2] - lo[2]);
    // The 8 corners, interpolated along x, then y, then z.
    const std::byte* d = data;
    const double c000 = Load<T>(d, base), c100 = Load<T>(d, base + 1);
    const double c010 = Load<T>(d, base + dy), c110 = Load<T>(d, base + dy + 1);
    const double c001 = Load<T>(d, base + dz), c101 = Load<T>(d, base + dz + 1);
    const double c011 = Load<T>(d, base + dz + dy), c111 = Load<T>(d, base + dz + dy + 1);
    const double c00 = Lerp(c000, c100, t[0]), c10 = Lerp(c010, c110, t[0]);
    const double c01 = Lerp(c001, c101, t[0]), c11 = Lerp(c011, c111, t[0]);
    return Lerp(Lerp(c00, c10, t[1]), Lerp(c01, c11, t[1]), t[2]);
  }
};

// The largest voxel magnitude a volume holds. Trilinear interpolation adds two products of
// values, and the default normalisation is max - min: values near the largest double (1.8e308)
// overflowed both, so that every error was inf (refinement ran to its tet budget) or 0
// ("converged" at once). Only float64 volumes can go beyond it.
inline constexpr double kMaxVoxelMagnitude = 1e300;

// A scalar voxel volume, or a slab of one: the samples with indices in [lo, hi) of a larger grid.
// Sampling uses the whole grid's geometry, so a point gives the same bits whether the volume is
// whole or a slab that contains the point's cell.
class Volume {
 public:
  // Checks geometry (dims, origin, spacing, direction: finite and invertible), range, data length
  // and values (finite, within +-kMaxVoxelMagnitude); errors name the field (e.g.
  // "volume.direction[4]"). `data` holds the slab's samples as little-endian values of `type`, x
  // fastest then y then z, size (hi-lo).prod() * VoxelSize(type) bytes.
  static absl::StatusOr<Volume> Create(const GridGeometry& grid, const Index3& lo, const Index3& hi,
                                       VoxelType type, std::vector<std::byte> data);
  // A whole volume: lo = 0, hi = grid.dims.
  static absl::StatusOr<Volume> CreateWhole(const GridGeometry& grid, VoxelType type,
                                            std::vector<std::byte> data);
  // Convenience for tests and generators: a whole float64 volume from values.
  static absl::StatusOr<Volume> FromDoubles(const GridGeometry& grid,
                                            const std::vector<double>& values);

  const GridGeometry& grid() const { return grid_; }
  const Index3& lo() const { return lo_; }
  const Index3& hi() const { return hi_; }
  VoxelType type() const { return type_; }
  const std::vector<std::byte>& data() const { return data_; }
  int64_t voxel_count() const;

  // The sample at grid index (i, j, k), which must lie in [lo, hi).
  double At(int64_t i, int64_t j, int64_t k) const;

  // Continuous grid index of a world point: (p - origin) / spacing per axis for the identity
  // direction (kept verbatim so axis-aligned results stay bit-identical), otherwise
  // (direction * diag(spacing))^-1 * (p - origin) with the inverse computed once in Create.
  Vec3 ContinuousIndex(const Vec3& p) const {
    return axis_aligned_ ? index_map().Apply<true>(p) : index_map().Apply<false>(p);
  }

  // The world-to-index map ContinuousIndex applies, by value.
  IndexMap index_map() const { return {grid_.origin, grid_.spacing, world_to_index_}; }

  // True when the grid's direction is the identity.
  bool axis_aligned() const { return axis_aligned_; }

  // The row-major 3x3 matrix ContinuousIndex applies to p - origin when the grid is oblique:
  // (direction * diag(spacing))^-1, computed once in Create. The identity when axis_aligned()
  // (then ContinuousIndex divides by the spacing instead). For peers that must repeat
  // ContinuousIndex to the bit (bench/peers/plaza_refine.py).
  const Mat3& world_to_index() const { return world_to_index_; }

  // A point this far (in voxels) outside the grid's own box still counts as inside it: meshes
  // built to span a volume land there by rounding (origin + 11 * 5.74 gives index 11 + 2e-15).
  // Grids far from the world origin with tiny voxels add the rounding of their world
  // coordinates (boundary_tolerance()).
  static constexpr double kGridBoundaryTolerance = 1e-6;

  // True when the continuous index u lies in the slab's sampled box [lo, hi - 1] on every axis
  // (widened by boundary_tolerance() on sides where the slab reaches the grid's boundary).
  bool Contains(const Vec3& u) const;

  // Per index axis, in voxels: kGridBoundaryTolerance plus 8 ulps of the grid's largest world
  // coordinate mapped to that axis. A function of the whole grid's geometry, the same for every
  // slab of it.
  const Vec3& boundary_tolerance() const { return boundary_tolerance_; }

  // Clamps a continuous index into the whole grid's box [0, dims - 1].
  Vec3 ClampToGrid(const Vec3& u) const;

  // Trilinear value (paper eq. 1) at continuous index u, which must satisfy Contains(u); u is
  // clamped to the grid's box first.
  // Evaluated as nested linear interpolations x, then y, then z: at a cell face the weight of the
  // far corners is exactly zero, so the neighbouring cell gives the same bits. That is what makes
  // a slab and the whole volume agree to the bit.
  double SampleIndex(const Vec3& u) const;

  // What SampleIndex reads, by value. The caller picks T = the voxel type of type().
  TrilinearSampler sampler() const;

  // The 8 samples at the corners of cell `cell` (its lowest corner; each axis in [lo, hi - 2]),
  // ordered c000, c100, c010, c110, c001, c101, c011, c111 (x fastest). For code that needs the
  // trilinear field of a whole cell, such as the exact maximum along a segment.
  std::array<double, 8> CellCorners(const Index3& cell) const;

  // The cell whose trilinear field holds at continuous index u: floor(u) clamped to the grid's
  // cells and then into the slab's, exactly as SampleIndex chooses it.
  Index3 CellOf(const Vec3& u) const;

  // Trilinear value at world point p (which must lie in the sampled box).
  double Sample(const Vec3& p) const { return SampleIndex(ContinuousIndex(p)); }

  // Smallest and largest sample of this volume (slab): the default normalisation range.
  std::array<double, 2> ValueRange() const;

 private:
  GridGeometry grid_;
  bool axis_aligned_ = true;
  Mat3 world_to_index_ = kIdentityDirection;  // (direction * diag(spacing))^-1 when oblique
  Vec3 boundary_tolerance_{kGridBoundaryTolerance, kGridBoundaryTolerance, kGridBoundaryTolerance};
  Index3 lo_{0, 0, 0};
  Index3 hi_{0, 0, 0};
  VoxelType type_ = VoxelType::kFloat64;
  std::vector<std::byte> data_;
};

}  // namespace tetrefine
