#include "client/io/nifti_writer.h"

#include <cmath>
#include <cstring>
#include <optional>

#include "absl/strings/match.h"
#include "absl/strings/str_cat.h"
#include "client/io/byte_order.h"
#include "client/io/file_bytes.h"
#include "client/io/io_error.h"
#include "client/io/zlib_codec.h"

namespace tetrefine::io {
namespace {

int16_t DatatypeOf(VoxelType type) {
  switch (type) {
    case VoxelType::kUint8:
      return 2;
    case VoxelType::kInt16:
      return 4;
    case VoxelType::kUint16:
      return 512;
    case VoxelType::kInt32:
      return 8;
    case VoxelType::kFloat32:
      return 16;
    case VoxelType::kFloat64:
      return 64;
  }
  return 0;
}

// Overwrites bytes [offset, offset + sizeof(T)) of `header` with `value`, little-endian.
template <typename T>
void Put(std::string& header, size_t offset, T value) {
  std::string raw;
  AppendLittle(raw, value);
  std::memcpy(header.data() + offset, raw.data(), raw.size());
}

struct Geometry {
  Index3 dims;
  Vec3 origin;
  Vec3 spacing;
  Mat3 direction = kIdentityDirection;
};

// The NIfTI qform of a direction: quaternion (b, c, d) and qfac, or nullopt when the direction is
// not orthonormal (sheared), which a qform cannot express; the sform still carries it exactly.
struct Quaternion {
  double b = 0.0, c = 0.0, d = 0.0, qfac = 1.0;
};

std::optional<Quaternion> QuaternionOf(const Mat3& direction) {
  Mat3 r = direction;
  Quaternion q;
  if (Determinant(r) < 0.0) {
    q.qfac = -1.0;
    for (int row = 0; row < 3; ++row) r[3 * row + 2] = -r[3 * row + 2];
  }
  // Orthonormal within float32 rounding, as files store it.
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      const double dot = r[i] * r[j] + r[3 + i] * r[3 + j] + r[6 + i] * r[6 + j];
      if (std::abs(dot - (i == j ? 1.0 : 0.0)) > 1e-6) return std::nullopt;
    }
  }
  auto at = [&](int row, int column) { return r[3 * row + column]; };
  // nifti_mat44_to_quatern's case analysis: divide by the largest component.
  double a = at(0, 0) + at(1, 1) + at(2, 2) + 1.0;
  if (a > 0.5) {
    a = 0.5 * std::sqrt(a);
    q.b = 0.25 * (at(2, 1) - at(1, 2)) / a;
    q.c = 0.25 * (at(0, 2) - at(2, 0)) / a;
    q.d = 0.25 * (at(1, 0) - at(0, 1)) / a;
  } else {
    const double xd = 1.0 + at(0, 0) - (at(1, 1) + at(2, 2));
    const double yd = 1.0 + at(1, 1) - (at(0, 0) + at(2, 2));
    const double zd = 1.0 + at(2, 2) - (at(0, 0) + at(1, 1));
    if (xd > 1.0) {
      q.b = 0.5 * std::sqrt(xd);
      q.c = 0.25 * (at(0, 1) + at(1, 0)) / q.b;
      q.d = 0.25 * (at(0, 2) + at(2, 0)) / q.b;
      a = 0.25 * (at(2, 1) - at(1, 2)) / q.b;
    } else if (yd > 1.0) {
      q.c = 0.5 * std::sqrt(yd);
      q.b = 0.25 * (at(0, 1) + at(1, 0)) / q.c;
      q.d = 0.25 * (at(1, 2) + at(2, 1)) / q.c;
      a = 0.25 * (at(0, 2) - at(2, 0)) / q.c;
    } else {
      q.d = 0.5 * std::sqrt(zd);
      q.b = 0.25 * (at(0, 2) + at(2, 0)) / q.d;
      q.c = 0.25 * (at(1, 2) + at(2, 1)) / q.d;
      a = 0.25 * (at(1, 0) - at(0, 1)) / q.d;
    }
    if (a < 0.0) {
      q.b = -q.b;
      q.c = -q.c;
      q.d = -q.d;
    }
  }
  return q;
}

std::string Nifti1Header(const Geometry& g, VoxelType type) {
  std::string h(352, '\0');  // header + 4-byte "no extensions" flag
  Put<int32_t>(h, 0, 348);
  h[38] = 'r';  // "regular", as ANALYZE readers expect
  Put<int16_t>(h, 40, 3);
  for (int a = 0; a < 3; ++a) Put<int16_t>(h, 42 + 2 * a, static_cast<int16_t>(g.dims[a]));
  for (int a = 3; a < 7; ++a) Put<int16_t>(h, 42 + 2 * a, 1);
  Put<int16_t>(h, 70, DatatypeOf(type));
  Put<int16_t>(h, 72, static_cast<int16_t>(8 * VoxelSize(type)));
  Put<float>(h, 76, 1.0f);  // qfac
  for (int a = 0; a < 3; ++a) Put<float>(h, 80 + 4 * a, static_cast<float>(g.spacing[a]));
  Put<float>(h, 108, 352.0f);
  Put<float>(h, 112, 1.0f);  // scl_slope: stored values are the values
  h[123] = 2;                // NIFTI_UNITS_MM
  std::memcpy(h.data() + 148, "tetrefine", 9);
  Put<int16_t>(h, 252, 1);  // qform_code: scanner
  Put<int16_t>(h, 254, 1);  // sform_code: scanner
  // Identity quaternion (b = c = d = 0).
  for (int a = 0; a < 3; ++a) Put<float>(h, 268 + 4 * a, static_cast<float>(g.origin[a]));
  for (int r = 0; r < 3; ++r) {
    Put<float>(h, 280 + 16 * r + 4 * r, static_cast<float>(g.spacing[r]));
    Put<float>(h, 280 + 16 * r + 12, static_cast<float>(g.origin[r]));
  }
  // Oblique: the sform is direction * diag(spacing); only then, so axis-aligned files keep
  // their bytes.
  if (!IsIdentityDirection(g.direction)) {
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) {
        Put<float>(h, 280 + 16 * r + 4 * c,
                   static_cast<float>(g.direction[3 * r + c] * g.spacing[c]));
      }
    }
    const std::optional<Quaternion> q = QuaternionOf(g.direction);
    if (!q.has_value()) Put<int16_t>(h, 252, 0);  // qform_code: unknown
    const Quaternion qq = q.value_or(Quaternion{});
    Put<float>(h, 76, static_cast<float>(qq.qfac));
    Put<float>(h, 256, static_cast<float>(qq.b));
    Put<float>(h, 260, static_cast<float>(qq.c));
    Put<float>(h, 264, static_cast<float>(qq.d));
  }
  std::memcpy(h.data() + 344, "n+1\0", 4);
  return h;
}

std::string Nifti2Header(const Geometry& g, VoxelType type) {
  std::string h(544, '\0');
  Put<int32_t>(h, 0, 540);
  std::memcpy(h.data() + 4, "n+2\0\r\n\032\n", 8);
  Put<int16_t>(h, 12, DatatypeOf(type));
  Put<int16_t>(h, 14, static_cast<int16_t>(8 * VoxelSize(type)));
  Put<int64_t>(h, 16, 3);
  for (int a = 0; a < 3; ++a) Put<int64_t>(h, 24 + 8 * a, g.dims[a]);
  for (int a = 3; a < 7; ++a) Put<int64_t>(h, 24 + 8 * a, 1);
  Put<double>(h, 104, 1.0);  // qfac
  for (int a = 0; a < 3; ++a) Put<double>(h, 112 + 8 * a, g.spacing[a]);
  Put<int64_t>(h, 168, 544);
  Put<double>(h, 176, 1.0);  // scl_slope
  std::memcpy(h.data() + 240, "tetrefine", 9);
  Put<int32_t>(h, 344, 1);  // qform_code
  Put<int32_t>(h, 348, 1);  // sform_code
  for (int a = 0; a < 3; ++a) Put<double>(h, 376 + 8 * a, g.origin[a]);
  for (int r = 0; r < 3; ++r) {
    Put<double>(h, 400 + 32 * r + 8 * r, g.spacing[r]);
    Put<double>(h, 400 + 32 * r + 24, g.origin[r]);
  }
  if (!IsIdentityDirection(g.direction)) {
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c)
        Put<double>(h, 400 + 32 * r + 8 * c, g.direction[3 * r + c] * g.spacing[c]);
    }
    const std::optional<Quaternion> q = QuaternionOf(g.direction);
    if (!q.has_value()) Put<int32_t>(h, 344, 0);  // qform_code: unknown
    const Quaternion qq = q.value_or(Quaternion{});
    Put<double>(h, 104, qq.qfac);
    Put<double>(h, 352, qq.b);
    Put<double>(h, 360, qq.c);
    Put<double>(h, 368, qq.d);
  }
  Put<int32_t>(h, 500, 2);  // NIFTI_UNITS_MM
  return h;
}

}  // namespace

absl::Status WriteNifti(const std::string& path, const Volume& volume,
                        const NiftiWriteOptions& options) {
  const bool gz = absl::EndsWithIgnoreCase(path, ".nii.gz");
  if (!gz && !absl::EndsWithIgnoreCase(path, ".nii")) {
    return FileError(path, "unknown extension for a NIfTI file: expected .nii or .nii.gz");
  }
  if (options.version != 1 && options.version != 2) {
    return FileError(path, absl::StrCat("NIfTI version ", options.version, " does not exist"));
  }
  const GridGeometry& grid = volume.grid();
  Geometry g;
  for (int a = 0; a < 3; ++a) {
    g.dims[a] = volume.hi()[a] - volume.lo()[a];
    g.spacing[a] = grid.spacing[a];
    if (options.version == 1 && g.dims[a] > 32767) {
      return FileError(path, absl::StrCat("axis ", a, " has ", g.dims[a],
                                          " samples, more than NIfTI-1 can store (32767); "
                                          "write NIfTI-2"));
    }
  }
  // A slab's sample (0, 0, 0) is the grid's sample lo.
  g.origin =
      WorldOfIndex(grid, {static_cast<double>(volume.lo()[0]), static_cast<double>(volume.lo()[1]),
                          static_cast<double>(volume.lo()[2])});
  g.direction = grid.direction;
  std::string bytes =
      options.version == 1 ? Nifti1Header(g, volume.type()) : Nifti2Header(g, volume.type());
  bytes.append(reinterpret_cast<const char*>(volume.data().data()), volume.data().size());
  if (gz) {
    absl::StatusOr<std::string> compressed = GzipCompress(bytes);
    if (!compressed.ok()) return WithPath(path, compressed.status());
    bytes = *std::move(compressed);
  }
  return WriteFileAtomically(path, bytes);
}

}  // namespace tetrefine::io
