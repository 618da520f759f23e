#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
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

// A scalar voxel volume, or a slab of one: the samples with indices in [lo, hi) of a larger grid.
// Sampling uses the whole grid's geometry, so a point gives the same bits whether the volume is
// whole or a slab that contains the point's cell.
class Volume {
 public:
  // Checks geometry (dims, origin, spacing, direction: finite and invertible), range and data
  // length; errors name the field (e.g. "volume.direction[4]"). `data` holds the slab's samples as
  // little-endian values of `type`, x fastest then y then z, size (hi-lo).prod() * VoxelSize(type)
  // bytes.
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
    if (axis_aligned_) {
      return {(p[0] - grid_.origin[0]) / grid_.spacing[0],
              (p[1] - grid_.origin[1]) / grid_.spacing[1],
              (p[2] - grid_.origin[2]) / grid_.spacing[2]};
    }
    const double d[3] = {p[0] - grid_.origin[0], p[1] - grid_.origin[1], p[2] - grid_.origin[2]};
    const Mat3& m = world_to_index_;
    return {m[0] * d[0] + m[1] * d[1] + m[2] * d[2], m[3] * d[0] + m[4] * d[1] + m[5] * d[2],
            m[6] * d[0] + m[7] * d[1] + m[8] * d[2]};
  }

  // True when the grid's direction is the identity.
  bool axis_aligned() const { return axis_aligned_; }

  // The row-major 3x3 matrix ContinuousIndex applies to p - origin when the grid is oblique:
  // (direction * diag(spacing))^-1, computed once in Create. The identity when axis_aligned()
  // (then ContinuousIndex divides by the spacing instead). For peers that must repeat
  // ContinuousIndex to the bit (bench/peers/plaza_refine.py).
  const Mat3& world_to_index() const { return world_to_index_; }

  // A point this far (in voxels) outside the grid's own box still counts as inside it: meshes
  // built to span a volume land there by rounding (origin + 11 * 5.74 gives index 11 + 2e-15).
  static constexpr double kGridBoundaryTolerance = 1e-6;

  // True when the continuous index u lies in the slab's sampled box [lo, hi - 1] on every axis
  // (widened by kGridBoundaryTolerance on sides where the slab reaches the grid's boundary).
  bool Contains(const Vec3& u) const;

  // Clamps a continuous index into the whole grid's box [0, dims - 1].
  Vec3 ClampToGrid(const Vec3& u) const;

  // Trilinear value (paper eq. 1) at continuous index u, which must satisfy Contains(u); u is
  // clamped to the grid's box first.
  // Evaluated as nested linear interpolations x, then y, then z: at a cell face the weight of the
  // far corners is exactly zero, so the neighbouring cell gives the same bits. That is what makes
  // a slab and the whole volume agree to the bit.
  double SampleIndex(const Vec3& u) const;

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
  Index3 lo_{0, 0, 0};
  Index3 hi_{0, 0, 0};
  VoxelType type_ = VoxelType::kFloat64;
  std::vector<std::byte> data_;
};

}  // namespace tetrefine
