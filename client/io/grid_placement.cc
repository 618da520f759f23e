#include "client/io/grid_placement.h"

#include <array>
#include <cmath>
#include <cstring>
#include <utility>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "client/io/io_error.h"

namespace tetrefine::io {
namespace {

double ColumnLength(const Affine& affine, int column) {
  return std::hypot(affine[0][column], affine[1][column], affine[2][column]);
}

bool IsDiagonalUpToSigns(const Affine& affine) {
  for (int column = 0; column < 3; ++column) {
    const double tolerance = kObliqueTolerance * ColumnLength(affine, column);
    for (int row = 0; row < 3; ++row) {
      if (row != column && std::abs(affine[row][column]) > tolerance) return false;
    }
  }
  return true;
}

// Reverses the sample order along every axis with flip[axis] set.
std::vector<std::byte> Flip(const std::vector<std::byte>& data, const Index3& dims, size_t width,
                            const std::array<bool, 3>& flip) {
  std::vector<std::byte> out(data.size());
  const int64_t nx = dims[0], ny = dims[1], nz = dims[2];
  for (int64_t k = 0; k < nz; ++k) {
    const int64_t sk = flip[2] ? nz - 1 - k : k;
    for (int64_t j = 0; j < ny; ++j) {
      const int64_t sj = flip[1] ? ny - 1 - j : j;
      const std::byte* src_row = data.data() + ((sk * ny + sj) * nx) * width;
      std::byte* dst_row = out.data() + ((k * ny + j) * nx) * width;
      if (!flip[0]) {
        std::memcpy(dst_row, src_row, nx * width);
        continue;
      }
      for (int64_t i = 0; i < nx; ++i) {
        std::memcpy(dst_row + i * width, src_row + (nx - 1 - i) * width, width);
      }
    }
  }
  return out;
}

// The first non-finite float sample, named by the file's own index (x fastest).
absl::Status CheckFiniteInFileOrder(absl::string_view path, const Index3& dims, VoxelType type,
                                    const std::vector<std::byte>& data) {
  if (type != VoxelType::kFloat32 && type != VoxelType::kFloat64) return absl::OkStatus();
  const int64_t count = dims[0] * dims[1] * dims[2];
  auto value_at = [&](int64_t i) {
    if (type == VoxelType::kFloat32) {
      float f = 0.0f;
      std::memcpy(&f, data.data() + i * 4, 4);
      return static_cast<double>(f);
    }
    double value = 0.0;
    std::memcpy(&value, data.data() + i * 8, 8);
    return value;
  };
  int64_t first = -1, non_finite = 0;
  for (int64_t i = 0; i < count; ++i) {
    if (std::isfinite(value_at(i))) continue;
    if (first < 0) first = i;
    ++non_finite;
  }
  if (first < 0) return absl::OkStatus();
  // Masked float maps (FSL's and SPM's, perfusion and PET maps) put NaN outside the tissue: say
  // how many there are and what to do, not only where the first is.
  const std::string others =
      non_finite > 1
          ? absl::StrCat(", and so are ", non_finite - 1, " other voxels (",
                         absl::StrFormat("%.3g", 100.0 * static_cast<double>(non_finite) /
                                                     static_cast<double>(count)),
                         "% of the volume)")
          : "";
  return FileError(
      path,
      absl::StrCat("voxel (", first % dims[0], ", ", (first / dims[0]) % dims[1], ", ",
                   first / (dims[0] * dims[1]), ") of the file is not finite (", value_at(first),
                   ")", others,
                   "; tetrefine needs a finite value at every voxel: replace NaN and Inf first "
                   "(e.g. numpy.nan_to_num, or fslmaths IN -nan OUT)"));
}

}  // namespace

absl::StatusOr<VolumeFile> PlaceOnGrid(absl::string_view path, const Affine& affine,
                                       const Index3& dims, VoxelType type,
                                       std::vector<std::byte> data) {
  for (int row = 0; row < 3; ++row) {
    for (int column = 0; column < 4; ++column) {
      if (!std::isfinite(affine[row][column])) {
        return FileError(path, "index-to-world transform has a non-finite entry");
      }
    }
  }
  std::array<double, 3> lengths;
  for (int column = 0; column < 3; ++column) {
    const double length = lengths[column] = ColumnLength(affine, column);
    if (!(length > 0.0)) {
      return FileError(path, absl::StrCat("index-to-world transform is singular: axis ", column,
                                          " has zero length"));
    }
    // No imaging device makes voxels outside this range, and at the extremes the geometry stops
    // being exact: fuzz_nifti found spacings of 1e-305 and 5e232 mm whose oblique columns
    // (direction x spacing) fall into subnormals, so writing the volume and reading it back gave
    // other bits (fuzz/corpus/nifti/regress-subnormal-spacing).
    if (length < kMinVoxelMm || length > kMaxVoxelMm) {
      return FileError(
          path, absl::StrCat("index-to-world transform: axis ", column, " is ", length,
                             " mm per voxel, outside [", kMinVoxelMm, ", ", kMaxVoxelMm, "] mm"));
    }
  }
  // The world coordinates must resolve the voxels: a DICOM series whose Image Position said
  // 1e17 mm was read with a world box [-1e17, -1e17] along x, every sample at one point, and a
  // mesh of it had zero volume (a sweep). Along each world axis, a corner farther from the world
  // origin than kMaxVoxelsFromOrigin of the voxels that step along that axis is refused.
  for (int row = 0; row < 3; ++row) {
    double voxel = kMaxVoxelMm;
    for (int column = 0; column < 3; ++column) {
      if (std::abs(affine[row][column]) > kObliqueTolerance * lengths[column]) {
        voxel = std::min(voxel, lengths[column]);
      }
    }
    for (int corner = 0; corner < 8; ++corner) {
      double x = affine[row][3];
      for (int column = 0; column < 3; ++column) {
        if ((corner >> column) & 1) {
          x += affine[row][column] * static_cast<double>(std::max<int64_t>(dims[column] - 1, 0));
        }
      }
      if (!(std::abs(x) <= kMaxVoxelsFromOrigin * voxel)) {
        return FileError(
            path, absl::StrCat("index-to-world transform puts a corner of the grid at ", x,
                               " mm along world axis ", row, ", more than 2^44 of its ", voxel,
                               " mm voxels from the world origin: float64 cannot place the "
                               "samples (check the origin or Image Position)"));
      }
    }
  }
  // Named by the file's own index (the core would name it by its grid index, which after a flip
  // is not the file's: (22, 10, 10) for the file's (10, 10, 10), found by a file-format sweep),
  // with how many there are and what to do.
  if (absl::Status finite = CheckFiniteInFileOrder(path, dims, type, data); !finite.ok()) {
    return finite;
  }
  VolumeFile result;
  result.affine = affine;
  GridGeometry grid;
  grid.dims = dims;
  if (IsDiagonalUpToSigns(affine)) {
    std::array<bool, 3> flip{};
    Index3 first{0, 0, 0};  // file index of the sample that becomes (0, 0, 0)
    for (int a = 0; a < 3; ++a) {
      flip[a] = affine[a][a] < 0.0;
      grid.spacing[a] = std::abs(affine[a][a]);
      if (flip[a]) first[a] = dims[a] - 1;
    }
    for (int row = 0; row < 3; ++row) {
      grid.origin[row] = affine[row][3];
      for (int column = 0; column < 3; ++column) {
        grid.origin[row] += affine[row][column] * static_cast<double>(first[column]);
      }
    }
    if (flip[0] || flip[1] || flip[2]) data = Flip(data, dims, VoxelSize(type), flip);
  } else {
    // Oblique: the samples stay in storage order and the rotation/shear/permutation goes into
    // the grid's direction, so volume.Sample(p) is the file's value at world point p.
    for (int column = 0; column < 3; ++column) {
      grid.spacing[column] = ColumnLength(affine, column);
      for (int row = 0; row < 3; ++row) {
        grid.direction[3 * row + column] = affine[row][column] / grid.spacing[column];
      }
    }
    for (int row = 0; row < 3; ++row) grid.origin[row] = affine[row][3];
  }
  absl::StatusOr<Volume> volume = Volume::CreateWhole(grid, type, std::move(data));
  if (!volume.ok()) return WithPath(path, volume.status());
  result.volume = *std::move(volume);
  return result;
}

}  // namespace tetrefine::io
