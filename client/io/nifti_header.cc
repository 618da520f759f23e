#include "client/io/nifti_header.h"

#include <algorithm>
#include <cmath>
#include <cstring>

#include "absl/strings/str_cat.h"
#include "client/io/io_error.h"

namespace tetrefine::io {
namespace {

// Reads consecutive fields from a header buffer in one byte order.
class FieldReader {
 public:
  FieldReader(absl::string_view bytes, ByteOrder order) : bytes_(bytes), order_(order) {}

  template <typename T>
  T At(size_t offset) const {
    return LoadAs<T>(bytes_, offset, order_);
  }

 private:
  absl::string_view bytes_;
  ByteOrder order_;
};

NiftiHeader ParseNifti1(const FieldReader& f) {
  NiftiHeader h;
  h.version = 1;
  for (int i = 0; i < 8; ++i) h.dim[i] = f.At<int16_t>(40 + 2 * i);
  h.datatype = f.At<int16_t>(70);
  for (int i = 0; i < 8; ++i) h.pixdim[i] = f.At<float>(76 + 4 * i);
  // vox_offset is a float in NIfTI-1; integral in every real file. A fraction would be dropped
  // without a word, and beyond int64 (or NaN) the conversion would be undefined: -1 makes the
  // reader refuse it, naming the value written.
  const float vox_offset = f.At<float>(108);
  h.vox_offset_written = vox_offset;
  h.vox_offset = vox_offset >= 0.0f && vox_offset < 0x1p62f && vox_offset == std::floor(vox_offset)
                     ? static_cast<int64_t>(vox_offset)
                     : -1;
  h.scl_slope = f.At<float>(112);
  h.scl_inter = f.At<float>(116);
  h.xyzt_units = f.At<uint8_t>(123);
  h.qform_code = f.At<int16_t>(252);
  h.sform_code = f.At<int16_t>(254);
  for (int i = 0; i < 3; ++i) h.quatern[i] = f.At<float>(256 + 4 * i);
  for (int i = 0; i < 3; ++i) h.qoffset[i] = f.At<float>(268 + 4 * i);
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 4; ++c) h.srow[r][c] = f.At<float>(280 + 16 * r + 4 * c);
  }
  return h;
}

NiftiHeader ParseNifti2(const FieldReader& f) {
  NiftiHeader h;
  h.version = 2;
  h.datatype = f.At<int16_t>(12);
  for (int i = 0; i < 8; ++i) h.dim[i] = f.At<int64_t>(16 + 8 * i);
  for (int i = 0; i < 8; ++i) h.pixdim[i] = f.At<double>(104 + 8 * i);
  h.vox_offset = f.At<int64_t>(168);
  h.vox_offset_written = static_cast<double>(h.vox_offset);
  h.scl_slope = f.At<double>(176);
  h.scl_inter = f.At<double>(184);
  h.qform_code = f.At<int32_t>(344);
  h.sform_code = f.At<int32_t>(348);
  for (int i = 0; i < 3; ++i) h.quatern[i] = f.At<double>(352 + 8 * i);
  for (int i = 0; i < 3; ++i) h.qoffset[i] = f.At<double>(376 + 8 * i);
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 4; ++c) h.srow[r][c] = f.At<double>(400 + 32 * r + 8 * c);
  }
  h.xyzt_units = f.At<int32_t>(500);
  return h;
}

// Millimetres per spatial unit of xyzt_units (bits 0-2).
double MillimetresPerUnit(int xyzt_units) {
  switch (xyzt_units & 0x07) {
    case 1:  // NIFTI_UNITS_METER
      return 1000.0;
    case 3:  // NIFTI_UNITS_MICRON
      return 0.001;
    default:  // NIFTI_UNITS_MM, or unknown: mm is what every neuroimaging tool assumes
      return 1.0;
  }
}

// The rotation of the NIfTI quaternion (b, c, d), with a = sqrt(1 - b^2 - c^2 - d^2).
std::array<std::array<double, 3>, 3> QuaternionRotation(double b, double c, double d) {
  double a = 1.0 - (b * b + c * c + d * d);
  if (a < 1e-7) {
    // Rounding pushed the norm past 1: a 180 degree rotation; renormalise (b, c, d) as
    // nifti1_io does.
    const double scale = 1.0 / std::sqrt(b * b + c * c + d * d);
    b *= scale;
    c *= scale;
    d *= scale;
    a = 0.0;
  } else {
    a = std::sqrt(a);
  }
  return {{{a * a + b * b - c * c - d * d, 2 * (b * c - a * d), 2 * (b * d + a * c)},
           {2 * (b * c + a * d), a * a + c * c - b * b - d * d, 2 * (c * d - a * b)},
           {2 * (b * d - a * c), 2 * (c * d + a * b), a * a + d * d - c * c - b * b}}};
}

}  // namespace

absl::StatusOr<NiftiHeader> ParseNiftiHeader(absl::string_view bytes, absl::string_view path) {
  if (bytes.size() < 4) {
    return FileError(
        path, absl::StrCat("truncated: ", bytes.size(), " bytes is too short for a NIfTI header"));
  }
  ByteOrder order = ByteOrder::kLittle;
  int32_t sizeof_hdr = LoadAs<int32_t>(bytes, 0, order);
  if (sizeof_hdr != 348 && sizeof_hdr != 540) {
    order = ByteOrder::kBig;
    sizeof_hdr = LoadAs<int32_t>(bytes, 0, order);
  }
  if (sizeof_hdr != 348 && sizeof_hdr != 540) {
    return FileError(path,
                     "not a NIfTI file: sizeof_hdr is neither 348 nor 540 in either byte "
                     "order");
  }
  const size_t header_size = static_cast<size_t>(sizeof_hdr);
  if (bytes.size() < header_size) {
    return FileError(path,
                     absl::StrCat("truncated: NIfTI-", sizeof_hdr == 348 ? 1 : 2, " header needs ",
                                  header_size, " bytes, file has ", bytes.size()));
  }
  const FieldReader fields(bytes, order);
  NiftiHeader header;
  if (sizeof_hdr == 348) {
    const absl::string_view magic = bytes.substr(344, 4);
    if (magic != absl::string_view("n+1\0", 4) && magic != absl::string_view("ni1\0", 4)) {
      return FileUnsupported(path,
                             "348-byte header without NIfTI-1 magic (ANALYZE 7.5 is not "
                             "read: it has no orientation)");
    }
    header = ParseNifti1(fields);
    header.single_file = magic[1] == '+';
  } else {
    const absl::string_view magic = bytes.substr(4, 8);
    if (magic != absl::string_view("n+2\0\r\n\032\n", 8) &&
        magic != absl::string_view("ni2\0\r\n\032\n", 8)) {
      return FileError(path,
                       "540-byte header without valid NIfTI-2 magic (a corrupted "
                       "transfer may have altered its line endings)");
    }
    header = ParseNifti2(fields);
    header.single_file = magic[1] == '+';
  }
  header.order = order;
  return header;
}

Affine NiftiAffine(const NiftiHeader& header, NiftiTransform* source) {
  const double mm = MillimetresPerUnit(header.xyzt_units);
  Affine affine{};
  affine[3][3] = 1.0;
  NiftiTransform used;
  if (header.sform_code > 0) {
    used = NiftiTransform::kSform;
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 4; ++c) affine[r][c] = header.srow[r][c] * mm;
    }
  } else if (header.qform_code > 0) {
    used = NiftiTransform::kQform;
    const auto rotation =
        QuaternionRotation(header.quatern[0], header.quatern[1], header.quatern[2]);
    const double qfac = header.pixdim[0] < 0.0 ? -1.0 : 1.0;
    const std::array<double, 3> scale{std::abs(header.pixdim[1]), std::abs(header.pixdim[2]),
                                      qfac * std::abs(header.pixdim[3])};
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) affine[r][c] = rotation[r][c] * scale[c] * mm;
      affine[r][3] = header.qoffset[r] * mm;
    }
  } else {
    used = NiftiTransform::kPixdimOnly;
    for (int a = 0; a < 3; ++a) {
      const double size = std::abs(header.pixdim[a + 1]);
      affine[a][a] = (size > 0.0 ? size : 1.0) * mm;
    }
  }
  if (source != nullptr) *source = used;
  return affine;
}

}  // namespace tetrefine::io
