#include "core/volume.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <limits>

#include "absl/status/status.h"
#include "absl/strings/str_cat.h"
#include "core/parallel.h"

namespace tetrefine {
namespace {

constexpr char kAxis[3] = {'x', 'y', 'z'};

// Voxel data is little-endian on the wire and in files; this build targets little-endian hosts.
static_assert(std::endian::native == std::endian::little, "tetrefine assumes a little-endian host");

using volume_internal::Load;

double LoadAs(VoxelType type, const std::byte* base, int64_t index) {
  switch (type) {
    case VoxelType::kUint8:
      return Load<uint8_t>(base, index);
    case VoxelType::kInt16:
      return Load<int16_t>(base, index);
    case VoxelType::kUint16:
      return Load<uint16_t>(base, index);
    case VoxelType::kInt32:
      return Load<int32_t>(base, index);
    case VoxelType::kFloat32:
      return Load<float>(base, index);
    case VoxelType::kFloat64:
      return Load<double>(base, index);
  }
  return 0.0;
}

// Inverse of a 3x3 matrix with a nonzero determinant, by the adjugate.
Mat3 Inverse(const Mat3& m) {
  const double det = Determinant(m);
  const Mat3 adj{m[4] * m[8] - m[5] * m[7], m[2] * m[7] - m[1] * m[8], m[1] * m[5] - m[2] * m[4],
                 m[5] * m[6] - m[3] * m[8], m[0] * m[8] - m[2] * m[6], m[2] * m[3] - m[0] * m[5],
                 m[3] * m[7] - m[4] * m[6], m[1] * m[6] - m[0] * m[7], m[0] * m[4] - m[1] * m[3]};
  Mat3 inv;
  for (int i = 0; i < 9; ++i) inv[i] = adj[i] / det;
  return inv;
}

}  // namespace

bool IsIdentityDirection(const Mat3& direction) {
  for (int i = 0; i < 9; ++i) {
    if (direction[i] != kIdentityDirection[i]) return false;
  }
  return true;
}

double Determinant(const Mat3& m) {
  return m[0] * (m[4] * m[8] - m[5] * m[7]) - m[1] * (m[3] * m[8] - m[5] * m[6]) +
         m[2] * (m[3] * m[7] - m[4] * m[6]);
}

DirectionDefect FindDirectionDefect(const Mat3& direction) {
  DirectionDefect defect;
  for (int i = 0; i < 9; ++i) {
    if (!std::isfinite(direction[i])) {
      defect.kind = DirectionDefect::Kind::kNotFinite;
      defect.index = i;
      return defect;
    }
  }
  Mat3 unit = direction;
  for (int column = 0; column < 3; ++column) {
    const double length = std::hypot(unit[column], unit[3 + column], unit[6 + column]);
    if (!(length > 0.0) || !std::isfinite(length)) {
      defect.kind = DirectionDefect::Kind::kZeroColumn;
      defect.index = column;
      return defect;
    }
    for (int row = 0; row < 3; ++row) unit[3 * row + column] /= length;
  }
  const double det = std::abs(Determinant(unit));
  if (!(det >= kMinDirectionDeterminant)) {
    defect.kind = DirectionDefect::Kind::kSingular;
    defect.det = det;
  }
  return defect;
}

Vec3 WorldOfIndex(const GridGeometry& grid, const Vec3& u) {
  if (IsIdentityDirection(grid.direction)) {
    return {grid.origin[0] + u[0] * grid.spacing[0], grid.origin[1] + u[1] * grid.spacing[1],
            grid.origin[2] + u[2] * grid.spacing[2]};
  }
  const Vec3 s{u[0] * grid.spacing[0], u[1] * grid.spacing[1], u[2] * grid.spacing[2]};
  const Mat3& d = grid.direction;
  Vec3 p;
  for (int row = 0; row < 3; ++row) {
    p[row] = grid.origin[row] + (d[3 * row] * s[0] + d[3 * row + 1] * s[1] + d[3 * row + 2] * s[2]);
  }
  return p;
}

std::array<Vec3, 8> WorldCorners(const GridGeometry& grid, const Vec3& lo, const Vec3& hi) {
  std::array<Vec3, 8> corners;
  for (int c = 0; c < 8; ++c) {
    corners[c] = WorldOfIndex(
        grid, {(c & 1) ? hi[0] : lo[0], (c & 2) ? hi[1] : lo[1], (c & 4) ? hi[2] : lo[2]});
  }
  return corners;
}

std::array<Vec3, 2> WorldBounds(const GridGeometry& grid, const Vec3& lo, const Vec3& hi) {
  const std::array<Vec3, 8> corners = WorldCorners(grid, lo, hi);
  std::array<Vec3, 2> box{corners[0], corners[0]};
  for (const Vec3& c : corners) {
    for (int a = 0; a < 3; ++a) {
      box[0][a] = std::min(box[0][a], c[a]);
      box[1][a] = std::max(box[1][a], c[a]);
    }
  }
  return box;
}

absl::StatusOr<Volume> Volume::Create(const GridGeometry& grid, const Index3& lo, const Index3& hi,
                                      VoxelType type, std::vector<std::byte> data) {
  // A bound on samples keeps the byte count below int64 overflow whatever the caller declares.
  constexpr int64_t kMaxAxis = int64_t{1} << 20;
  for (int a = 0; a < 3; ++a) {
    if (grid.dims[a] < 2 || grid.dims[a] > kMaxAxis) {
      return absl::InvalidArgumentError(absl::StrCat("volume.dims.", std::string(1, kAxis[a]),
                                                     " = ", grid.dims[a],
                                                     ": must be in [2, 2^20] (trilinear needs a "
                                                     "cell)"));
    }
    if (!std::isfinite(grid.origin[a])) {
      return absl::InvalidArgumentError(
          absl::StrCat("volume.origin.", std::string(1, kAxis[a]), " is not finite"));
    }
    // A subnormal spacing's inverse overflows: every point then mapped to an infinite index and
    // passed the inside test (a request with spacing 1e-310 was accepted and every vertex read
    // the boundary's value; found 2026-11-28 by a review of the Python client).
    if (!std::isfinite(grid.spacing[a]) ||
        !(grid.spacing[a] >= std::numeric_limits<double>::min())) {
      return absl::InvalidArgumentError(
          absl::StrCat("volume.spacing.", std::string(1, kAxis[a]), " = ", grid.spacing[a],
                       ": must be finite and at least ", std::numeric_limits<double>::min(),
                       " (the smallest normal double; its inverse must be finite)"));
    }
    if (lo[a] < 0 || hi[a] > grid.dims[a] || hi[a] - lo[a] < 2) {
      return absl::InvalidArgumentError(absl::StrCat(
          "volume slab range on ", std::string(1, kAxis[a]), " is [", lo[a], ", ", hi[a],
          "): must lie in [0, ", grid.dims[a], ") and hold at least 2 samples"));
    }
  }
  switch (const DirectionDefect defect = FindDirectionDefect(grid.direction); defect.kind) {
    case DirectionDefect::Kind::kNone:
      break;
    case DirectionDefect::Kind::kNotFinite:
      return absl::InvalidArgumentError(absl::StrCat("volume.direction[", defect.index, "] (row ",
                                                     defect.index / 3, ", column ",
                                                     defect.index % 3, ") is not finite"));
    case DirectionDefect::Kind::kZeroColumn:
      return absl::InvalidArgumentError(
          absl::StrCat("volume.direction column ", defect.index,
                       " is zero (or overflows): the index axis has no world direction"));
    case DirectionDefect::Kind::kSingular:
      return absl::InvalidArgumentError(
          absl::StrCat("volume.direction is singular: |det| of its normalised columns is ",
                       defect.det, ", must be >= ", kMinDirectionDeterminant));
  }
  const int64_t count = (hi[0] - lo[0]) * (hi[1] - lo[1]) * (hi[2] - lo[2]);
  const uint64_t expected = static_cast<uint64_t>(count) * VoxelSize(type);
  if (data.size() != expected) {
    return absl::InvalidArgumentError(
        absl::StrCat("volume data holds ", data.size(), " bytes; the slab needs ", expected, " (",
                     count, " ", std::string(VoxelTypeName(type)), " voxels)"));
  }
  Volume v;
  v.grid_ = grid;
  v.axis_aligned_ = IsIdentityDirection(grid.direction);
  if (!v.axis_aligned_) {
    Mat3 scaled = grid.direction;
    for (int i = 0; i < 9; ++i) scaled[i] *= grid.spacing[i % 3];
    v.world_to_index_ = Inverse(scaled);
  }
  // The boundary tolerance grows with the rounding of the world coordinates themselves: a mesh
  // vertex placed on the grid's last sample at origin 1e7 mm with 1e-4 mm voxels rounds to
  // index 9 + 7e-6, beyond the fixed 1e-6 (found by a CLI sweep: `tetrefine mesh` wrote a
  // mesh `refine` then refused). A few ulps of the largest world coordinate of the grid, mapped to
  // index units by the world-to-index rows. It depends on the whole grid's geometry only, so a
  // slab gets the same tolerance as the whole volume; for ordinary grids the added term is about
  // 1e-13 voxels.
  {
    Vec3 last;
    for (int a = 0; a < 3; ++a) last[a] = static_cast<double>(grid.dims[a] - 1);
    double scale = 0.0;
    for (const Vec3& c : WorldCorners(grid, {0.0, 0.0, 0.0}, last)) {
      for (int a = 0; a < 3; ++a) scale = std::max(scale, std::abs(c[a]));
    }
    // Corners beyond float64 (a huge origin, or spacing times dims) made the tolerance infinite
    // and every point "inside", as a subnormal spacing did.
    if (!std::isfinite(scale)) {
      return absl::InvalidArgumentError(
          "volume grid: its far corner, origin + direction * spacing * (dims - 1), overflows "
          "float64");
    }
    for (int a = 0; a < 3; ++a) {
      double row = 0.0;
      for (int b = 0; b < 3; ++b) {
        row += v.axis_aligned_ ? (a == b ? 1.0 / grid.spacing[a] : 0.0)
                               : std::abs(v.world_to_index_[3 * a + b]);
      }
      v.boundary_tolerance_[a] =
          kGridBoundaryTolerance + 8.0 * std::numeric_limits<double>::epsilon() * scale * row;
      // An index map that overflows would make the tolerance infinite, and every point
      // "inside" (the corners were checked above).
      if (!std::isfinite(v.boundary_tolerance_[a])) {
        return absl::InvalidArgumentError(
            absl::StrCat("volume grid: its world-to-index map overflows float64 on axis ",
                         std::string(1, kAxis[a]), " (spacing ", grid.spacing[a], ")"));
      }
    }
  }
  v.lo_ = lo;
  v.hi_ = hi;
  v.type_ = type;
  v.data_ = std::move(data);
  if (type == VoxelType::kFloat32 || type == VoxelType::kFloat64) {
    for (int64_t i = 0; i < count; ++i) {
      const double value = LoadAs(type, v.data_.data(), i);
      if (!(std::abs(value) <= kMaxVoxelMagnitude)) {
        // Named by its grid index, as a user's viewer shows it, not by its place in the slab.
        const int64_t nx = hi[0] - lo[0], ny = hi[1] - lo[1];
        return absl::InvalidArgumentError(absl::StrCat(
            "volume voxel (", lo[0] + i % nx, ", ", lo[1] + (i / nx) % ny, ", ",
            lo[2] + i / (nx * ny), ") ",
            std::isfinite(value)
                ? absl::StrCat("is ", value, ": beyond +-", kMaxVoxelMagnitude,
                               " the interpolation and the value range overflow; rescale the "
                               "volume")
                : absl::StrCat("is not finite (", value, ")")));
      }
    }
  }
  return v;
}

absl::StatusOr<Volume> Volume::CreateWhole(const GridGeometry& grid, VoxelType type,
                                           std::vector<std::byte> data) {
  return Create(grid, Index3{0, 0, 0}, grid.dims, type, std::move(data));
}

absl::StatusOr<Volume> Volume::FromDoubles(const GridGeometry& grid,
                                           const std::vector<double>& values) {
  std::vector<std::byte> bytes(values.size() * sizeof(double));
  std::memcpy(bytes.data(), values.data(), bytes.size());
  return CreateWhole(grid, VoxelType::kFloat64, std::move(bytes));
}

int64_t Volume::voxel_count() const {
  return (hi_[0] - lo_[0]) * (hi_[1] - lo_[1]) * (hi_[2] - lo_[2]);
}

double Volume::At(int64_t i, int64_t j, int64_t k) const {
  const int64_t nx = hi_[0] - lo_[0], ny = hi_[1] - lo_[1];
  const int64_t index = (i - lo_[0]) + nx * ((j - lo_[1]) + ny * (k - lo_[2]));
  return LoadAs(type_, data_.data(), index);
}

bool Volume::Contains(const Vec3& u) const {
  for (int a = 0; a < 3; ++a) {
    double lo = static_cast<double>(lo_[a]);
    double hi = static_cast<double>(hi_[a] - 1);
    // Only where the slab ends at the grid's own boundary: inside the grid a slab must hold the
    // cell, or it would not sample the same bits as the whole volume.
    if (lo_[a] == 0) lo -= boundary_tolerance_[a];
    if (hi_[a] == grid_.dims[a]) hi += boundary_tolerance_[a];
    // Written so that NaN fails the test.
    if (!(u[a] >= lo && u[a] <= hi)) return false;
  }
  return true;
}

Vec3 Volume::ClampToGrid(const Vec3& u) const {
  Vec3 c;
  for (int a = 0; a < 3; ++a) {
    c[a] = std::clamp(u[a], 0.0, static_cast<double>(grid_.dims[a] - 1));
  }
  return c;
}

TrilinearSampler Volume::sampler() const {
  const int64_t nx = hi_[0] - lo_[0], ny = hi_[1] - lo_[1];
  TrilinearSampler s;
  s.data = data_.data();
  for (int a = 0; a < 3; ++a) {
    s.max_index[a] = static_cast<double>(grid_.dims[a] - 1);
    s.lo[a] = lo_[a];
    s.max_cell[a] = hi_[a] - 2;
  }
  s.dy = nx;
  s.dz = nx * ny;
  return s;
}

double Volume::SampleIndex(const Vec3& u) const {
  const TrilinearSampler s = sampler();
  switch (type_) {
    case VoxelType::kUint8:
      return s.Sample<uint8_t>(u);
    case VoxelType::kInt16:
      return s.Sample<int16_t>(u);
    case VoxelType::kUint16:
      return s.Sample<uint16_t>(u);
    case VoxelType::kInt32:
      return s.Sample<int32_t>(u);
    case VoxelType::kFloat32:
      return s.Sample<float>(u);
    case VoxelType::kFloat64:
      return s.Sample<double>(u);
  }
  return 0.0;
}

namespace {

template <typename T>
std::array<double, 8> CornersOf(const std::byte* d, int64_t base, int64_t dy, int64_t dz) {
  return {Load<T>(d, base),           Load<T>(d, base + 1),          Load<T>(d, base + dy),
          Load<T>(d, base + dy + 1),  Load<T>(d, base + dz),         Load<T>(d, base + dz + 1),
          Load<T>(d, base + dz + dy), Load<T>(d, base + dz + dy + 1)};
}

}  // namespace

std::array<double, 8> Volume::CellCorners(const Index3& cell) const {
  const int64_t nx = hi_[0] - lo_[0], ny = hi_[1] - lo_[1];
  const int64_t base = (cell[0] - lo_[0]) + nx * ((cell[1] - lo_[1]) + ny * (cell[2] - lo_[2]));
  const int64_t dy = nx, dz = nx * ny;
  const std::byte* d = data_.data();
  switch (type_) {
    case VoxelType::kUint8:
      return CornersOf<uint8_t>(d, base, dy, dz);
    case VoxelType::kInt16:
      return CornersOf<int16_t>(d, base, dy, dz);
    case VoxelType::kUint16:
      return CornersOf<uint16_t>(d, base, dy, dz);
    case VoxelType::kInt32:
      return CornersOf<int32_t>(d, base, dy, dz);
    case VoxelType::kFloat32:
      return CornersOf<float>(d, base, dy, dz);
    case VoxelType::kFloat64:
      return CornersOf<double>(d, base, dy, dz);
  }
  return {};
}

Index3 Volume::CellOf(const Vec3& u) const {
  Index3 cell;
  for (int a = 0; a < 3; ++a) {
    const double x = std::clamp(u[a], 0.0, static_cast<double>(grid_.dims[a] - 1));
    cell[a] = std::clamp(static_cast<int64_t>(x), lo_[a], hi_[a] - 2);
  }
  return cell;
}

namespace {

template <typename T>
std::array<double, 2> RangeOf(const std::byte* data, int64_t n) {
  const int64_t blocks = BlockCount(n);
  std::vector<std::array<double, 2>> partial(blocks);
  ForEachBlock(n, [&](int64_t b, int64_t begin, int64_t end) {
    double lo = Load<T>(data, begin), hi = lo;
    for (int64_t i = begin + 1; i < end; ++i) {
      const double v = Load<T>(data, i);
      lo = std::min(lo, v);
      hi = std::max(hi, v);
    }
    partial[b] = {lo, hi};
  });
  std::array<double, 2> range = partial[0];
  for (const auto& [lo, hi] : partial) range = {std::min(range[0], lo), std::max(range[1], hi)};
  return range;
}

}  // namespace

std::array<double, 2> Volume::ValueRange() const {
  // In parallel and typed: it runs on every request that does not pass norm_coeff.
  const int64_t n = voxel_count();
  const std::byte* d = data_.data();
  switch (type_) {
    case VoxelType::kUint8:
      return RangeOf<uint8_t>(d, n);
    case VoxelType::kInt16:
      return RangeOf<int16_t>(d, n);
    case VoxelType::kUint16:
      return RangeOf<uint16_t>(d, n);
    case VoxelType::kInt32:
      return RangeOf<int32_t>(d, n);
    case VoxelType::kFloat32:
      return RangeOf<float>(d, n);
    case VoxelType::kFloat64:
      return RangeOf<double>(d, n);
  }
  return {0.0, 0.0};
}

}  // namespace tetrefine
