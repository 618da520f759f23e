#include "client/io/nifti_reader.h"

#include <cmath>
#include <optional>
#include <utility>

#include "absl/strings/match.h"
#include "absl/strings/str_cat.h"
#include "client/io/file_bytes.h"
#include "client/io/grid_placement.h"
#include "client/io/io_error.h"
#include "client/io/nifti_header.h"
#include "client/io/voxel_decode.h"

namespace tetrefine::io {
namespace {

// NIfTI's datatype codes (nifti1.h, NIFTI_TYPE_*) of the scalar types read; int8, uint32, int64
// and uint64 widen exactly (DecodeVoxels): nibabel writes an int8 mask as int8 and keeps a label
// map's uint32.
std::optional<StoredType> StoredTypeOfDatatype(int datatype) {
  switch (datatype) {
    case 2:
      return StoredType::kUint8;
    case 4:
      return StoredType::kInt16;
    case 8:
      return StoredType::kInt32;
    case 16:
      return StoredType::kFloat32;
    case 64:
      return StoredType::kFloat64;
    case 256:
      return StoredType::kInt8;
    case 512:
      return StoredType::kUint16;
    case 768:
      return StoredType::kUint32;
    case 1024:
      return StoredType::kInt64;
    case 1280:
      return StoredType::kUint64;
    default:
      return std::nullopt;
  }
}

absl::string_view DatatypeName(int datatype) {
  switch (datatype) {
    case 1:
      return "binary";
    case 32:
      return "complex64";
    case 128:
      return "rgb24";
    case 1536:
      return "float128";
    case 1792:
      return "complex128";
    case 2048:
      return "complex256";
    case 2304:
      return "rgba32";
    default:
      return "unknown";
  }
}

// "x.hdr" -> "x.img", "x.hdr.gz" -> "x.img.gz".
std::string ImagePathFor(const std::string& header_path) {
  const bool gz = absl::EndsWithIgnoreCase(header_path, ".gz");
  const size_t stem = header_path.size() - (gz ? 7 : 4);
  const bool upper = header_path[stem + 1] == 'H';
  return absl::StrCat(header_path.substr(0, stem), upper ? ".IMG" : ".img", gz ? ".gz" : "");
}

absl::StatusOr<Index3> SpatialDims(const NiftiHeader& header, absl::string_view path) {
  const int64_t rank = header.dim[0];
  if (rank < 1 || rank > 7) {
    return FileError(path, absl::StrCat("dim[0] = ", rank, ": must be in [1, 7]"));
  }
  Index3 dims{1, 1, 1};
  for (int a = 1; a <= rank; ++a) {
    const int64_t size = header.dim[a];
    if (size < 1 || size > kMaxVolumeAxis) {
      return FileError(path, absl::StrCat("dim[", a, "] = ", size, ": must be in [1, 2^20]"));
    }
    if (a <= 3) {
      dims[a - 1] = size;
    } else if (size != 1) {
      // A 4D series (fMRI, DCE or DSC perfusion) is common input: say how to take one frame.
      // dim[5] is, by the NIfTI-1 standard, the values stored per voxel (a vector, tensor or
      // displacement image, nibabel's shape (x, y, z, 1, n)): not a series, and said so.
      std::string what;
      if (a == 4) {
        what = absl::StrCat("a ", rank, "D series of ", size,
                            " frames; take one first, e.g. frame k with `fslroi IN OUT k 1` or "
                            "nibabel's `image.slicer[..., k]`");
      } else if (a == 5) {
        what = absl::StrCat(size,
                            " values per voxel (dim[5]: a vector, tensor or displacement image); "
                            "take one component first, e.g. component c with nibabel's "
                            "`image.dataobj[..., 0, c]`");
      } else {
        what = absl::StrCat("a ", rank, "D image");
      }
      return FileUnsupported(path, absl::StrCat("dim[", a, "] = ", size,
                                                ": only 3D volumes of one value per voxel are "
                                                "read (this is ",
                                                what, ")"));
    }
  }
  return dims;
}

}  // namespace

absl::StatusOr<VolumeFile> ReadNifti(const std::string& path) {
  absl::StatusOr<std::string> file = ReadFileMaybeGzip(path);
  if (!file.ok()) return file.status();
  absl::StatusOr<NiftiHeader> header = ParseNiftiHeader(*file, path);
  if (!header.ok()) return header.status();

  const bool is_header_file =
      absl::EndsWithIgnoreCase(path, ".hdr") || absl::EndsWithIgnoreCase(path, ".hdr.gz");
  std::string image_path = path;
  std::string image_storage;
  absl::string_view image = *file;
  if (!header->single_file) {
    if (!is_header_file) {
      return FileError(path,
                       "header says the samples are in a separate .img file (magic "
                       "ni1/ni2), but this is not a .hdr file");
    }
    image_path = ImagePathFor(path);
    absl::StatusOr<std::string> img = ReadFileMaybeGzip(image_path);
    if (!img.ok()) return WithPath(path, img.status());
    image_storage = *std::move(img);
    image = image_storage;
  }

  absl::StatusOr<Index3> dims = SpatialDims(*header, path);
  if (!dims.ok()) return dims.status();
  const std::optional<StoredType> type = StoredTypeOfDatatype(header->datatype);
  if (!type.has_value()) {
    return FileUnsupported(
        path,
        absl::StrCat("NIfTI datatype ", header->datatype, " (", DatatypeName(header->datatype),
                     ") is not supported; supported: uint8, int8, int16, uint16, int32, "
                     "uint32, int64, uint64, float32, float64"));
  }
  // The standard asks for 352 / 544 (room for the extension flag); old writers used the bare
  // header size, which is still unambiguous.
  const size_t min_offset =
      header->single_file ? (header->version == 1 ? kNifti1HeaderSize : kNifti2HeaderSize) : 0;
  if (header->vox_offset < 0 || static_cast<uint64_t>(header->vox_offset) < min_offset) {
    const double written = header->vox_offset_written;
    return FileError(
        path, absl::StrCat("vox_offset = ", written, ": ",
                           written >= 0x1p62
                               ? absl::StrCat("beyond the data file's ", image.size(), " bytes")
                               : absl::StrCat("must be a whole number of bytes, at "
                                              "least ",
                                              min_offset)));
  }
  const uint64_t offset = static_cast<uint64_t>(header->vox_offset);
  // Each axis is at most 2^20, so the product fits in 2^60 and times 8 bytes in uint64.
  const uint64_t count = static_cast<uint64_t>((*dims)[0]) * static_cast<uint64_t>((*dims)[1]) *
                         static_cast<uint64_t>((*dims)[2]);
  const uint64_t need = count * StoredSize(*type);
  const uint64_t have = image.size() > offset ? image.size() - offset : 0;
  if (have < need) {
    return FileError(
        image_path, absl::StrCat("truncated: header says ", need, " voxel bytes at offset ", offset,
                                 ", file has ", have));
  }
  // A slope that is not a number is no scaling, as niftilib (nifti1_io.c: FIXED_FLOAT) and
  // nibabel read it; the CLI refused such a file that Python's volume_from_nibabel took
  // (a review, 2026-11-28). Said, as the values then are the stored ones. A valid slope with an
  // intercept that is not a number stays refused (DecodeVoxels), as nibabel refuses it.
  double slope = header->scl_slope, inter = header->scl_inter;
  std::string scaling_warning;
  if (!std::isfinite(slope)) {
    scaling_warning = absl::StrCat(path, ": scl_slope is ", slope,
                                   ", not a scaling: the stored values are read unscaled (as "
                                   "niftilib and nibabel read them)");
    slope = 0.0;
    inter = 0.0;
  }
  absl::StatusOr<DecodedVoxels> voxels =
      DecodeVoxels(image.substr(offset, need), *type, header->order, slope, inter);
  if (!voxels.ok()) return WithPath(path, voxels.status());
  NiftiTransform transform;
  const Affine affine = NiftiAffine(*header, &transform);
  absl::StatusOr<VolumeFile> placed =
      PlaceOnGrid(path, affine, *dims, voxels->type, std::move(voxels->data));
  if (placed.ok() && !scaling_warning.empty()) placed->warnings.push_back(scaling_warning);
  if (const int unit = header->xyzt_units & 0x07; placed.ok() && (unit == 1 || unit == 3)) {
    // The standard's units, as niftilib and ITK apply them; nibabel ignores them, so a mesh
    // made in its coordinates would not line up. Applied without a word until an outside
    // review (2026-11-29) noticed.
    placed->warnings.push_back(
        absl::StrCat(path, ": xyzt_units says ", unit == 1 ? "metres" : "micrometres",
                     ": coordinates are scaled to millimetres (x", unit == 1 ? "1000" : "0.001",
                     "), as niftilib and ITK read them; nibabel does not scale them"));
  }
  if (placed.ok() && transform == NiftiTransform::kPixdimOnly) {
    // The standard's method 1 places such a file with voxel (0, 0, 0) at the origin, as niftilib
    // does; nibabel centres it and mirrors x (its "base affine"), so a mesh made in nibabel's
    // world coordinates is somewhere else here. Said, since `info` called such a file
    // unremarkable (a file-format sweep, 2026-11-28).
    placed->warnings.push_back(absl::StrCat(
        path,
        ": no qform or sform (both codes 0): placed by pixdim alone, voxel (0, 0, 0) at the "
        "origin, as the NIfTI standard's method 1 says; nibabel centres such a volume and "
        "mirrors x, so meshes made in its coordinates will not line up"));
    // Without qform or sform the spacing is pixdim; a zero or non-finite one is read as 1 (as
    // nibabel does). Said, since every distance in the result then depends on it.
    for (int a = 0; a < 3; ++a) {
      const double size = std::abs(header->pixdim[a + 1]);
      if (!(size > 0.0) || !std::isfinite(size)) {
        placed->warnings.push_back(absl::StrCat(path, ": pixdim[", a + 1, "] is ",
                                                header->pixdim[a + 1],
                                                " and the file has no qform or sform: voxel size 1 "
                                                "used along axis ",
                                                a));
      }
    }
  }
  return placed;
}

}  // namespace tetrefine::io
