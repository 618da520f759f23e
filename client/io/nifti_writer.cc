#include "client/io/nifti_writer.h"

#include <cstring>

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
};

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
    g.origin[a] = grid.origin[a] + static_cast<double>(volume.lo()[a]) * grid.spacing[a];
    if (options.version == 1 && g.dims[a] > 32767) {
      return FileError(path, absl::StrCat("axis ", a, " has ", g.dims[a],
                                          " samples, more than NIfTI-1 can store (32767); "
                                          "write NIfTI-2"));
    }
  }
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
