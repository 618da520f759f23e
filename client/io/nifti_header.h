#pragma once

#include <array>
#include <cstddef>
#include <cstdint>

#include "absl/status/statusor.h"
#include "absl/strings/string_view.h"
#include "client/io/byte_order.h"
#include "client/io/volume_file.h"

namespace tetrefine::io {

// The fields of a NIfTI-1 (348-byte) or NIfTI-2 (540-byte) header that placing and decoding the
// samples needs, widened to the NIfTI-2 types.
struct NiftiHeader {
  int version = 1;  // 1 or 2
  ByteOrder order = ByteOrder::kLittle;
  bool single_file = true;          // magic n+1/n+2 (.nii) rather than ni1/ni2 (.hdr + .img)
  std::array<int64_t, 8> dim{};     // dim[0] = rank, dim[1..7] = sizes
  int datatype = 0;                 // NIFTI_TYPE_* code
  std::array<double, 8> pixdim{};   // pixdim[0] = qfac, pixdim[1..3] = voxel size in xyz units
  int64_t vox_offset = 0;           // byte offset of the samples in the data file; -1 when the
                                    // header's is not a whole number in [0, 2^62)
  double vox_offset_written = 0.0;  // the header's vox_offset as written, for messages
  double scl_slope = 0.0;
  double scl_inter = 0.0;
  int xyzt_units = 0;
  int qform_code = 0;
  int sform_code = 0;
  std::array<double, 3> quatern{};  // b, c, d
  std::array<double, 3> qoffset{};  // x, y, z
  std::array<std::array<double, 4>, 3> srow{};
};

// NIfTI-1 header size; a NIfTI-2 header is 540 bytes.
inline constexpr size_t kNifti1HeaderSize = 348;
inline constexpr size_t kNifti2HeaderSize = 540;

// Parses the header at the start of `bytes`. The byte order is detected from sizeof_hdr (348 or
// 540 in either order), as the NIfTI standard recommends.
absl::StatusOr<NiftiHeader> ParseNiftiHeader(absl::string_view bytes, absl::string_view path);

// Which header transform the affine came from, for messages.
enum class NiftiTransform { kSform, kQform, kPixdimOnly };

// The index-to-world (RAS mm) affine the NIfTI standard prescribes: sform when sform_code > 0,
// else qform when qform_code > 0, else the ANALYZE fallback diag(pixdim) with no offset. Spatial
// units from xyzt_units are converted to millimetres (unknown units are taken as mm).
Affine NiftiAffine(const NiftiHeader& header, NiftiTransform* source = nullptr);

}  // namespace tetrefine::io
