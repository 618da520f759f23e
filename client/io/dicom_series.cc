#include "client/io/dicom_series.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <set>
#include <utility>
#include <vector>

#include "absl/strings/match.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/strings/str_join.h"
#include "client/io/dicom_file.h"
#include "client/io/file_bytes.h"
#include "client/io/grid_placement.h"
#include "client/io/io_error.h"
#include "client/io/voxel_decode.h"
#include "client/io/world_frame.h"

namespace tetrefine::io {
namespace {

constexpr absl::string_view kDicomDirClass = "1.2.840.10008.1.3.10";
// Files a directory may hold: a series has at most kMaxVolumeAxis slices; the margin allows
// the other files beside them. More means a wrong directory, not a series.
constexpr size_t kMaxDirectoryFiles = size_t{1} << 21;
// Orientation cosines of two slices of one series agree to this (they are written with about
// six digits); pixel spacings to this fraction.
constexpr double kOrientationTolerance = 1e-4;
constexpr double kSpacingTolerance = 1e-4;
// A slice may lie this fraction of the slice step off the line through the first and the last
// (IPP values carry about six digits; a missing slice is a whole step off).
constexpr double kPositionTolerance = 0.01;

struct Slice {
  std::string file;
  DicomImage image;        // pixel_data cleared: the file is read again for its pixels
  size_t pixel_bytes = 0;  // the size of its file's Pixel Data
  double along = 0;        // Image Position (Patient) along the slice normal, mm
  int64_t frame = -1;      // its frame in a multi-frame file (FrameOf); -1: none
  // Why its file cannot be a stack of slices (CheckNmFile), found before its frames were
  // expanded; CheckPlaceable returns it if the slice is of the series read.
  absl::Status problem = absl::OkStatus();
};

using Vec = std::array<double, 3>;

Vec Cross(const Vec& a, const Vec& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}
double Dot(const Vec& a, const Vec& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
double Norm(const Vec& a) { return std::sqrt(Dot(a, a)); }

std::string FileName(const std::string& file) {
  return std::filesystem::path(file).filename().string();
}

// A slice for messages: its file's name, and its frame in a multi-frame file (1-based, as
// viewers count them).
std::string SliceName(const Slice& s) {
  std::string name = FileName(s.file);
  if (s.frame >= 0) absl::StrAppend(&name, " frame ", s.frame + 1);
  return name;
}

// The directory a file is in ("." for a bare name).
std::string ParentDirectory(const std::string& file) {
  const std::string parent = std::filesystem::path(file).parent_path().string();
  return parent.empty() ? std::string(".") : parent;
}

// The regular files of `directory` (links followed), sorted by name so that every message and
// tie is the same from run to run.
absl::StatusOr<std::vector<std::string>> FilesIn(const std::string& directory) {
  std::vector<std::string> files;
  std::error_code ec;
  std::filesystem::directory_iterator it(directory, ec);
  if (ec) return FileError(directory, absl::StrCat("cannot list the directory: ", ec.message()));
  for (; it != std::filesystem::directory_iterator(); it.increment(ec)) {
    if (ec) return FileError(directory, absl::StrCat("cannot list the directory: ", ec.message()));
    std::error_code kind_ec;
    if (!it->is_regular_file(kind_ec)) continue;
    if (files.size() == kMaxDirectoryFiles) {
      return FileError(directory, absl::StrCat("holds more than ", kMaxDirectoryFiles,
                                               " files: not the directory of one series"));
    }
    files.push_back(it->path().string());
  }
  if (ec) return FileError(directory, absl::StrCat("cannot list the directory: ", ec.message()));
  std::sort(files.begin(), files.end());
  return files;
}

// Whether the file starts like DICOM (HasDicomMagic), reading only its first 132 bytes.
bool FileHasDicomMagic(const std::string& file) {
  std::ifstream in(file, std::ios::binary);
  char head[132];
  in.read(head, sizeof(head));
  return HasDicomMagic(absl::string_view(head, static_cast<size_t>(in.gcount())));
}

// Checks that `s` matches the series' first slice in everything that shapes the grid.
absl::Status CheckSameShape(const Slice& first, const Slice& s) {
  const DicomImage& a = first.image;
  const DicomImage& b = s.image;
  const auto differ = [&](absl::string_view what, double x, double y) {
    return FileError(s.file, absl::StrCat("DICOM ", what, " is ", y,
                                          s.frame >= 0 ? absl::StrCat(" in frame ", s.frame + 1)
                                                       : std::string(" here"),
                                          " but ", x, " in ", SliceName(first),
                                          " of the same series: its slices must agree"));
  };
  if (a.rows != b.rows) return differ("Rows (0028,0010)", a.rows, b.rows);
  if (a.columns != b.columns) return differ("Columns (0028,0011)", a.columns, b.columns);
  if (a.bits_allocated != b.bits_allocated) {
    return differ("Bits Allocated (0028,0100)", a.bits_allocated, b.bits_allocated);
  }
  if (StoredBits(a) != StoredBits(b)) {
    return differ("Bits Stored (0028,0101)", StoredBits(a), StoredBits(b));
  }
  if (a.pixel_representation != b.pixel_representation) {
    return differ("Pixel Representation (0028,0103)", a.pixel_representation,
                  b.pixel_representation);
  }
  for (int c = 0; c < 6; ++c) {
    if (std::abs((*a.orientation)[c] - (*b.orientation)[c]) > kOrientationTolerance) {
      return differ(absl::StrCat("Image Orientation (Patient) (0020,0037) value ", c + 1),
                    (*a.orientation)[c], (*b.orientation)[c]);
    }
  }
  for (int c = 0; c < 2; ++c) {
    const double x = (*a.pixel_spacing)[c], y = (*b.pixel_spacing)[c];
    if (std::abs(x - y) > kSpacingTolerance * std::max(x, y)) {
      return differ(absl::StrCat("Pixel Spacing (0028,0030) value ", c + 1), x, y);
    }
  }
  return absl::OkStatus();
}

// The bytes of one frame's samples (0 when Rows, Columns or Bits Allocated say none).
uint64_t FrameBytes(const DicomImage& im) {
  return static_cast<uint64_t>(std::max<int64_t>(im.rows, 0)) *
         static_cast<uint64_t>(std::max<int64_t>(im.columns, 0)) *
         static_cast<uint64_t>(std::max(im.bits_allocated, 0) / 8);
}

// What a tag of a Frame Increment Pointer (0028,0009) is called (PS3.3 C.8.4.8, C.7.6.6).
std::string FrameVectorName(uint32_t tag) {
  struct Known {
    uint32_t tag;
    absl::string_view name;
  };
  static constexpr Known kKnown[] = {
      {0x00540010, "Energy Window Vector"}, {0x00540020, "Detector Vector"},
      {0x00540030, "Phase Vector"},         {0x00540050, "Rotation Vector"},
      {0x00540060, "R-R Interval Vector"},  {0x00540070, "Time Slot Vector"},
      {0x00540080, "Slice Vector"},         {0x00540090, "Angular View Vector"},
      {0x00540100, "Time Slice Vector"},    {0x00181063, "Frame Time"},
      {0x00181065, "Frame Time Vector"},
  };
  const std::string tag_text =
      TagText(static_cast<uint16_t>(tag >> 16), static_cast<uint16_t>(tag & 0xFFFF));
  for (const Known& k : kKnown) {
    if (k.tag == tag) return absl::StrCat(k.name, " ", tag_text);
  }
  return tag_text;
}

// Checks, before its frames become slices, what an NM reconstruction (FrameStack::kNmSlices)
// needs beyond each slice's own attributes: well-formed NM attributes, a spacing that stacks the
// frames, a Slice Vector (when given) naming each slice once, and the pixels of every frame.
// Checked first because each frame becomes a slice record: a 932-byte file claiming a million
// frames of 1 x 1 samples took 1.1 GB before its missing pixels were seen (found by a review).
absl::Status CheckNmFile(const std::string& file, const DicomImage& im, size_t pixel_bytes) {
  if (!im.nm_problem.empty()) return FileError(file, absl::StrCat("DICOM ", im.nm_problem));
  if (!NmStackingOf(im).spacing) {
    return FileError(file, absl::StrCat("DICOM file holds ", im.frames,
                                        " NM slices (Frame Increment Pointer (0028,0009) is Slice "
                                        "Vector (0054,0080)) but neither a usable Spacing Between "
                                        "Slices (0018,0088) (one non-zero number) nor a positive "
                                        "Slice Thickness (0018,0050) that would stack them"));
  }
  const uint64_t frame_bytes = FrameBytes(im);
  if (frame_bytes == 0) {
    return FileError(
        file, absl::StrCat("DICOM image is ", im.columns, " x ", im.rows, " (Columns x Rows) of ",
                           im.bits_allocated, " bits allocated: its frames are empty"));
  }
  const uint64_t need = frame_bytes * static_cast<uint64_t>(im.frames);
  if (pixel_bytes < need) {
    return FileError(
        file, absl::StrCat("DICOM Pixel Data (7FE0,0010) has ", pixel_bytes, " bytes, its ",
                           im.frames, " frames need ", need, " (", im.columns, " x ", im.rows,
                           " samples of ", im.bits_allocated, " bits a frame)"));
  }
  if (!im.slice_vector) return absl::OkStatus();
  const std::vector<uint16_t>& slices = *im.slice_vector;
  if (static_cast<int64_t>(slices.size()) != im.frames) {
    return FileError(file, absl::StrCat("DICOM Slice Vector (0054,0080) has ", slices.size(),
                                        " values for ", im.frames,
                                        " frames (Number of Frames (0028,0008)): one a frame "
                                        "is needed"));
  }
  std::vector<int64_t> frame_of(static_cast<size_t>(im.frames) + 1, -1);
  for (size_t f = 0; f < slices.size(); ++f) {
    const uint16_t slice = slices[f];
    if (slice < 1 || slice > im.frames) {
      return FileError(file, absl::StrCat("DICOM Slice Vector (0054,0080) value ", f + 1, " is ",
                                          slice, ", not a slice from 1 to ", im.frames));
    }
    if (frame_of[slice] >= 0) {
      return FileError(file, absl::StrCat("DICOM Slice Vector (0054,0080) names slice ", slice,
                                          " for frames ", frame_of[slice] + 1, " and ", f + 1,
                                          ": each slice must be one frame's"));
    }
    frame_of[slice] = static_cast<int64_t>(f);
  }
  return absl::OkStatus();
}

// What a reader of an NM reconstruction should know of how it was placed: position or
// orientation given twice and differing (this reader follows the Detector Information Sequence,
// where the NM modules put them; dcm2niix takes the top level), or several detector items.
void NoteNmPlacement(const std::string& file, const DicomImage& im,
                     std::vector<std::string>* warnings) {
  const auto differs = [](const auto& a, const auto& b, double tolerance) {
    if (!a || !b) return false;
    for (size_t c = 0; c < a->size(); ++c) {
      if (std::abs((*a)[c] - (*b)[c]) > tolerance) return true;
    }
    return false;
  };
  if (differs(im.position, im.detector_position, 1e-3) ||
      differs(im.orientation, im.detector_orientation, kOrientationTolerance)) {
    warnings->push_back(absl::StrCat(
        file,
        ": the top level's Image Position or Orientation (Patient) differs from the Detector "
        "Information Sequence's (0054,0022); the sequence's places the NM slices, as the NM "
        "modules put them there (dcm2niix takes the top level's)"));
  }
  if (im.detector_items > 1) {
    warnings->push_back(absl::StrCat(file, ": the Detector Information Sequence (0054,0022) has ",
                                     im.detector_items, " items; the first places the NM slices"));
  }
  if (NmStackingOf(im).from_thickness) {
    warnings->push_back(absl::StrCat(
        file,
        ": no usable Spacing Between Slices (0018,0088) (absent, zero or not one number); the NM "
        "slices are stacked by Slice Thickness (0018,0050), as contiguous slices"));
  }
}

// Checks what a slice must have to be placed and decoded.
absl::Status CheckPlaceable(const Slice& s) {
  if (!s.problem.ok()) return s.problem;
  const DicomImage& im = s.image;
  const auto missing = [&](absl::string_view what) {
    return FileError(
        s.file,
        absl::StrCat("DICOM ",
                     s.frame < 0 ? std::string("image") : absl::StrCat("frame ", s.frame + 1),
                     " has no ", what,
                     s.frame < 0 ? ""
                     : FrameStackOf(im) == FrameStack::kNmSlices
                         ? " (nor does its Detector Information Sequence (0054,0022))"
                         : " (nor do the shared functional groups)",
                     ": its slices cannot be placed in the world"));
  };
  if (s.frame < 0 && im.frames != 1) {
    if (!im.nm_problem.empty() && im.frame_group_count() == 0) {
      return FileError(s.file, absl::StrCat("DICOM ", im.nm_problem));
    }
    if (!im.frame_increment_pointer.empty() && im.frame_group_count() == 0) {
      std::vector<std::string> vectors;
      for (const uint32_t tag : im.frame_increment_pointer) vectors.push_back(FrameVectorName(tag));
      return FileUnsupported(
          s.file,
          absl::StrCat("DICOM file holds ", im.frames, " frames indexed by ",
                       absl::StrJoin(vectors, ", "),
                       " (Frame Increment Pointer (0028,0009)): not the slices of one volume. "
                       "Frames are read as slices in an enhanced multi-frame file and when Slice "
                       "Vector (0054,0080) alone indexes them (a reconstructed NM tomography, "
                       "Image Type RECON TOMO); a cine or a gated, dynamic, planar or projection "
                       "file is not one volume (dcm2niix converts what can be)"));
    }
    if (im.frame_group_count() > 0) {
      return FileError(s.file,
                       absl::StrCat("DICOM file holds ", im.frames,
                                    " frames (Number of Frames (0028,0008)) but its Per-frame "
                                    "Functional Groups Sequence (5200,9230) has ",
                                    im.frame_group_count(), " items: one per frame is needed"));
    }
    return FileUnsupported(
        s.file,
        absl::StrCat("DICOM file holds ", im.frames,
                     " frames (Number of Frames (0028,0008)) but no Per-frame Functional Groups "
                     "Sequence (5200,9230) nor Frame Increment Pointer (0028,0009): only "
                     "enhanced multi-frame images, whose frames carry their positions, and NM "
                     "reconstructions, whose Frame Increment Pointer is Slice Vector (0054,0080), "
                     "are read; convert the series to NIfTI with dcm2niix"));
  }
  if (!im.position) return missing("Image Position (Patient) (0020,0032)");
  if (!im.orientation) return missing("Image Orientation (Patient) (0020,0037)");
  if (!im.pixel_spacing) return missing("Pixel Spacing (0028,0030)");
  if (im.samples_per_pixel != 1) {
    return FileUnsupported(
        s.file, absl::StrCat("DICOM Samples per Pixel (0028,0002) is ", im.samples_per_pixel,
                             ": colour images are not read, only scalar ones"));
  }
  if (im.rows < 1 || im.columns < 1) {
    return FileError(s.file, absl::StrCat("DICOM image is ", im.columns, " x ", im.rows,
                                          " (Columns x Rows): empty"));
  }
  if (im.bits_allocated != 8 && im.bits_allocated != 16 && im.bits_allocated != 32) {
    return FileUnsupported(s.file, absl::StrCat("DICOM Bits Allocated (0028,0100) is ",
                                                im.bits_allocated, ": only 8, 16 and 32 are read"));
  }
  // PS3.3 C.7.6.3.1.1: from 1 to Bits Allocated. A file saying 0 was read as if it had no Bits
  // Stored (all the allocated bits), a guess at a malformed value (found by a sweep).
  if (StoredBits(im) < 1 || StoredBits(im) > im.bits_allocated) {
    return FileError(s.file, absl::StrCat("DICOM Bits Stored (0028,0101) is ", StoredBits(im),
                                          ": a sample stores from 1 to Bits Allocated (",
                                          im.bits_allocated, ") bits"));
  }
  if (im.pixel_representation != 0 && im.pixel_representation != 1) {
    return FileError(s.file, absl::StrCat("DICOM Pixel Representation (0028,0103) is ",
                                          im.pixel_representation, ", expected 0 or 1"));
  }
  const Vec row{(*im.orientation)[0], (*im.orientation)[1], (*im.orientation)[2]};
  const Vec col{(*im.orientation)[3], (*im.orientation)[4], (*im.orientation)[5]};
  if (std::abs(Norm(row) - 1) > 1e-3 || std::abs(Norm(col) - 1) > 1e-3 ||
      std::abs(Dot(row, col)) > 1e-3) {
    return FileError(s.file,
                     "DICOM Image Orientation (Patient) (0020,0037) is not two orthogonal unit "
                     "vectors");
  }
  for (int c = 0; c < 2; ++c) {
    const double sp = (*im.pixel_spacing)[c];
    if (!(sp > 0)) {
      return FileError(s.file, absl::StrCat("DICOM Pixel Spacing (0028,0030) value ", c + 1, " is ",
                                            sp, ", not positive"));
    }
  }
  const uint64_t need = FrameBytes(im) * static_cast<uint64_t>(s.frame < 0 ? 1 : s.frame + 1);
  if (s.pixel_bytes < need) {
    return FileError(
        s.file, absl::StrCat("DICOM Pixel Data (7FE0,0010) has ", s.pixel_bytes, " bytes, ",
                             s.frame < 0 ? std::string("the image needs ")
                                         : absl::StrCat("its first ", s.frame + 1, " frames need "),
                             need, " (", im.columns, " x ", im.rows, " samples of ",
                             im.bits_allocated, " bits", s.frame < 0 ? "" : " a frame", ")"));
  }
  return absl::OkStatus();
}

// The samples' storage type before any rescaling, and whether they need widening first: 8-bit
// signed samples to int16 and 32-bit unsigned ones to float64 (Volume has neither type).
VoxelType UnscaledType(const DicomImage& im) {
  const bool is_signed = im.pixel_representation == 1;
  switch (im.bits_allocated) {
    case 8:
      return is_signed ? VoxelType::kInt16 : VoxelType::kUint8;
    case 16:
      return is_signed ? VoxelType::kInt16 : VoxelType::kUint16;
    default:
      return is_signed ? VoxelType::kInt32 : VoxelType::kFloat64;
  }
}

// Sample `n` of raw little-endian pixel data, masked to its stored bits and sign-extended.
int64_t StoredSample(const DicomImage& im, absl::string_view pixels, size_t n) {
  const int bytes = im.bits_allocated / 8;
  uint64_t raw = 0;
  std::memcpy(&raw, pixels.data() + n * bytes, bytes);  // little endian host (byte_order.h)
  const int bits = StoredBits(im);
  const uint64_t mask = bits >= 64 ? ~uint64_t{0} : (uint64_t{1} << bits) - 1;
  raw &= mask;
  if (im.pixel_representation == 1 && (raw >> (bits - 1)) != 0) raw |= ~mask;
  return static_cast<int64_t>(raw);
}

// Writes the `count` stored samples of one slice to `out` as T, scaled by the slice's own
// Rescale Slope and Intercept when `rescale`.
template <typename T>
void GatherSlice(const DicomImage& im, absl::string_view pixels, size_t count, std::byte* out,
                 bool rescale = false) {
  for (size_t m = 0; m < count; ++m) {
    const int64_t v = StoredSample(im, pixels, m);
    const T x =
        rescale ? static_cast<T>(im.rescale_slope * static_cast<double>(v) + im.rescale_intercept)
                : static_cast<T>(v);
    std::memcpy(out + m * sizeof(T), &x, sizeof(T));
  }
}

}  // namespace

bool IsDicomPath(const std::string& path) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) return true;
  if (absl::EndsWithIgnoreCase(path, ".dcm") || absl::EndsWithIgnoreCase(path, ".dicom")) {
    return true;
  }
  return std::filesystem::is_regular_file(path, ec) && FileHasDicomMagic(path);
}

absl::StatusOr<VolumeFile> ReadDicomSeries(const std::string& path) {
  std::error_code ec;
  const bool is_directory = std::filesystem::is_directory(path, ec);
  std::string directory = path;
  std::optional<std::string> wanted_series;
  if (!is_directory) {
    absl::StatusOr<FileView> view = FileView::Open(path);
    if (!view.ok()) return view.status();
    absl::StatusOr<DicomImage> image = ParseDicomFile(view->bytes(), path);
    if (!image.ok()) return image.status();
    if (!image->unsupported.empty()) return FileUnsupported(path, image->unsupported);
    if (!image->pixel_data) {
      return FileError(path, "DICOM file holds no image (no Pixel Data (7FE0,0010))");
    }
    wanted_series = image->series_uid;
    directory = ParentDirectory(path);
  }
  absl::StatusOr<std::vector<std::string>> files = FilesIn(directory);
  if (!files.ok()) return files.status();

  // First pass: every file's header, grouped by series. Files that are not DICOM images, or
  // that this reader cannot read (a compressed dose screen, a deflated report, an interrupted
  // copy beside the series), are skipped and counted: a sweep had a valid series refused for
  // such a neighbour. If one was a slice of the series, the gap it leaves is found below, and
  // the message then mentions the unreadable files.
  std::map<std::string, std::vector<Slice>> series;
  std::map<std::string, std::set<std::string>> instances;  // per series: SOP Instance UIDs
  int64_t not_dicom = 0, no_image = 0, duplicates = 0;
  std::map<std::string, std::string> compressed;  // series -> why one of its images is refused
  int64_t unreadable = 0;
  std::string first_unreadable;          // "file: why" of the first"
  std::vector<std::string> nm_warnings;  // how NM files were placed (NoteNmPlacement)
  for (const std::string& file : *files) {
    absl::StatusOr<FileView> view = FileView::Open(file);
    if (!view.ok()) return view.status();
    if (!HasDicomMagic(view->bytes())) {
      ++not_dicom;
      continue;
    }
    absl::StatusOr<DicomImage> image = ParseDicomFile(view->bytes(), file);
    if (!image.ok()) {
      if (unreadable++ == 0) first_unreadable = std::string(image.status().message());
      continue;
    }
    if (image->media_sop_class == kDicomDirClass ||
        (!image->pixel_data && image->unsupported.empty())) {
      ++no_image;
      continue;
    }
    if (wanted_series && image->series_uid != *wanted_series) continue;
    if (!image->unsupported.empty()) {
      // A compressed image: refused if it belongs to the series read, skipped otherwise.
      compressed[image->series_uid] = image->unsupported;
      continue;
    }
    // The same image exported twice ("IM0003 (1).dcm"): one copy is read.
    if (!image->sop_instance_uid.empty() &&
        !instances[image->series_uid].insert(image->sop_instance_uid).second) {
      ++duplicates;
      continue;
    }
    // The pixels are read again in the second pass, so that no file stays mapped.
    const size_t pixel_bytes = image->pixel_data->size();
    image->pixel_data.reset();
    std::vector<Slice>& slices = series[image->series_uid];
    // An enhanced multi-frame file is a stack of slices, one per frame, each placed by its own
    // functional groups, and so is an NM reconstruction, its frames stacked along the normal
    // (FrameOf); another multi-frame file (cine, gated or planar NM) is refused by
    // CheckPlaceable.
    const int64_t frames = image->frames;
    const FrameStack stack = FrameStackOf(*image);
    if (stack == FrameStack::kNmSlices) {
      if (absl::Status st = CheckNmFile(file, *image, pixel_bytes); !st.ok()) {
        slices.push_back(Slice{file, FrameOf(*image, 0), pixel_bytes, 0.0, -1, st});
        continue;
      }
      NoteNmPlacement(file, *image, &nm_warnings);
    }
    if (stack != FrameStack::kNone) {
      if (static_cast<int64_t>(slices.size()) + frames > kMaxVolumeAxis) {
        return FileError(file, absl::StrCat("DICOM file holds ", frames, " frames, more than ",
                                            kMaxVolumeAxis, " slices"));
      }
      for (int64_t f = 0; f < frames; ++f) {
        slices.push_back(Slice{file, FrameOf(*image, f), pixel_bytes, 0.0, f});
      }
    } else if (frames > 1) {
      // Refused by CheckPlaceable if it is in the series read, which names what is missing.
      slices.push_back(Slice{file, *std::move(image), pixel_bytes, 0.0});
    } else {
      slices.push_back(Slice{file, FrameOf(*image, 0), pixel_bytes, 0.0});
    }
  }
  // Said after an error about the series, when files were skipped as unreadable.
  const std::string unreadable_note =
      unreadable == 0
          ? std::string()
          : absl::StrCat(" (", unreadable, " files of the directory could not be read, e.g. ",
                         first_unreadable, ")");
  const auto series_error = [&](const std::string& where, absl::string_view problem) {
    return FileError(where, absl::StrCat(problem, unreadable_note));
  };
  if (series.empty() && compressed.size() == 1) {
    return FileUnsupported(path, compressed.begin()->second);
  }
  if (series.empty()) {
    // Exports often hold one directory per series under a patient or study directory.
    bool has_subdirectories = false;
    for (const auto& entry : std::filesystem::directory_iterator(directory, ec)) {
      std::error_code kind_ec;
      if (entry.is_directory(kind_ec)) has_subdirectories = true;
    }
    return FileError(
        path,
        absl::StrCat("no DICOM image found (", files->size(), " files: ", not_dicom, " not DICOM, ",
                     no_image, " without an image, ", unreadable, " unreadable",
                     unreadable == 0 ? "" : absl::StrCat(", e.g. ", first_unreadable), ")",
                     has_subdirectories
                         ? "; subdirectories are not searched: name the directory of one "
                           "series, or one of its files"
                         : ""));
  }
  if (series.size() > 1) {
    std::string list;
    int shown = 0;
    for (const auto& [uid, slices] : series) {
      if (shown++ == 4) {
        absl::StrAppend(&list, ", ...");
        break;
      }
      const DicomImage& im = slices.front().image;
      absl::StrAppend(
          &list, shown > 1 ? "; " : "",
          im.series_number.empty() ? "" : absl::StrCat("series ", im.series_number, " "),
          im.series_description.empty() ? "" : absl::StrCat("\"", im.series_description, "\" "),
          uid.empty() ? "(no UID)" : Printable(uid), ": ", slices.size(), " images, e.g. ",
          FileName(slices.front().file));
    }
    return FileError(path, absl::StrCat("directory holds ", series.size(), " DICOM series (", list,
                                        "): name one file of the series to read instead of the "
                                        "directory"));
  }
  std::vector<Slice>& slices = series.begin()->second;
  if (const auto it = compressed.find(series.begin()->first); it != compressed.end()) {
    return FileUnsupported(path, it->second);
  }

  for (const Slice& s : slices) {
    if (absl::Status st = CheckPlaceable(s); !st.ok()) return st;
    if (absl::Status st = CheckSameShape(slices.front(), s); !st.ok()) return st;
  }
  if (slices.size() < 2) {
    return series_error(slices.front().file,
                        "the DICOM series has a single slice: a volume needs at least two");
  }
  if (slices.size() > static_cast<size_t>(kMaxVolumeAxis)) {
    return FileError(path, absl::StrCat("the DICOM series has ", slices.size(),
                                        " slices, more than ", kMaxVolumeAxis));
  }

  const DicomImage& first = slices.front().image;
  const Vec row{(*first.orientation)[0], (*first.orientation)[1], (*first.orientation)[2]};
  const Vec col{(*first.orientation)[3], (*first.orientation)[4], (*first.orientation)[5]};
  const Vec normal = Cross(row, col);
  for (Slice& s : slices) s.along = Dot(*s.image.position, normal);
  // By position along the normal; equal positions are refused below, so the order is fixed by
  // geometry alone.
  std::stable_sort(slices.begin(), slices.end(),
                   [](const Slice& a, const Slice& b) { return a.along < b.along; });
  // Two slices at one position are closer than a thousandth of the mean step. (A thousandth of
  // the in-plane spacing called frames 1.5 mm apart one position when the pixels were 1e5 mm,
  // found by a sweep.) All at one position: a mean step of 0, every gap 0.
  const double mean_step =
      (slices.back().along - slices.front().along) / static_cast<double>(slices.size() - 1);
  for (size_t k = 1; k < slices.size(); ++k) {
    if (slices[k].along - slices[k - 1].along <= 1e-3 * mean_step) {
      return FileError(
          path, absl::StrCat("DICOM slices ", SliceName(slices[k - 1]), " and ",
                             SliceName(slices[k]), " lie at the same position (", slices[k].along,
                             " mm along the slice normal): the series holds several volumes "
                             "(time points, echoes or b-values); split it, e.g. with dcm2niix"));
    }
  }
  const size_t n = slices.size();
  const Vec p0 = *slices.front().image.position;
  const Vec pn = *slices.back().image.position;
  Vec step;
  for (int a = 0; a < 3; ++a) step[a] = (pn[a] - p0[a]) / static_cast<double>(n - 1);
  const double step_length = Norm(step);
  // Even spacing along the normal: the gap between neighbours that departs most from the mean
  // gap names the two slices around it (a missing slice leaves a gap of twice the others; a
  // sweep found the first slice off the line named instead).
  const double mean_gap = (slices.back().along - slices.front().along) / static_cast<double>(n - 1);
  const auto gap = [&](size_t k) { return slices[k + 1].along - slices[k].along; };
  size_t worst = 0;
  for (size_t k = 1; k + 1 < n; ++k) {
    if (std::abs(gap(k) - mean_gap) > std::abs(gap(worst) - mean_gap)) worst = k;
  }
  if (std::abs(gap(worst) - mean_gap) > kPositionTolerance * mean_gap) {
    return series_error(
        path,
        absl::StrCat("DICOM slice spacing is uneven: ", SliceName(slices[worst]), " and ",
                     SliceName(slices[worst + 1]), " are ", absl::StrFormat("%.4g", gap(worst)),
                     " mm apart along the slice normal, where the series averages ",
                     absl::StrFormat("%.4g", mean_gap),
                     " mm (a missing slice, or a series of varying spacing; dcm2niix can "
                     "resample it)"));
  }
  // The positions must also lie on one line: an in-plane drift (a gantry tilt) makes a sheared
  // grid only when it is the same from slice to slice.
  for (size_t k = 1; k + 1 < n; ++k) {
    const Vec& p = *slices[k].image.position;
    Vec off;
    for (int a = 0; a < 3; ++a) off[a] = p[a] - (p0[a] + static_cast<double>(k) * step[a]);
    if (Norm(off) > kPositionTolerance * step_length) {
      return series_error(
          path, absl::StrCat("DICOM slice positions do not lie on one line: ", SliceName(slices[k]),
                             " lies ", absl::StrFormat("%.4g", Norm(off)),
                             " mm off the line through the first and last slices (a varying "
                             "gantry tilt, or a mixed series)"));
    }
  }

  // Index (i, j, k) = (column, row, slice). Pixel Spacing is (between rows, between columns).
  std::array<Vec, 3> axes;
  for (int a = 0; a < 3; ++a) {
    axes[0][a] = row[a] * (*first.pixel_spacing)[1];
    axes[1][a] = col[a] * (*first.pixel_spacing)[0];
    axes[2][a] = step[a];
  }
  const Affine affine = LpsToRas(AffineFromAxes(axes, p0));
  const Index3 dims{first.columns, first.rows, static_cast<int64_t>(n)};

  // Second pass: the samples, slice by slice in position order.
  const size_t per_slice = static_cast<size_t>(first.columns * first.rows);
  bool one_scaling = true;
  for (const Slice& s : slices) {
    const double slope = s.image.rescale_slope, inter = s.image.rescale_intercept;
    if (slope == 0.0) {
      return FileError(s.file,
                       "DICOM Rescale Slope (0028,1053) is 0: every value would be the "
                       "intercept");
    }
    one_scaling = one_scaling && slope == first.rescale_slope && inter == first.rescale_intercept;
  }
  const VoxelType stored = UnscaledType(first);
  const bool scaled = !one_scaling || first.rescale_slope != 1.0 || first.rescale_intercept != 0.0;
  // Scaled values of one scaling go through DecodeVoxels (float32 for at most 16 bits, as a
  // NIfTI with scl_slope reads); per-slice scalings (PET) and scaled 32-bit samples are float64.
  const bool to_float64 = !one_scaling || (scaled && first.bits_allocated == 32);
  const VoxelType gathered = to_float64 ? VoxelType::kFloat64 : stored;
  std::vector<std::byte> data(per_slice * n * VoxelSize(gathered));
  // The frames of a multi-frame file come one after another in position order, mostly: the
  // file read last is kept open for the next slice.
  std::optional<FileView> view;
  std::optional<DicomImage> image;
  std::string open_file;
  for (size_t k = 0; k < n; ++k) {
    const Slice& s = slices[k];
    if (!view || open_file != s.file) {
      image.reset();
      view.reset();
      absl::StatusOr<FileView> opened = FileView::Open(s.file);
      if (!opened.ok()) return opened.status();
      view = *std::move(opened);
      absl::StatusOr<DicomImage> parsed = ParseDicomFile(view->bytes(), s.file);
      if (!parsed.ok()) return parsed.status();
      image = *std::move(parsed);
      open_file = s.file;
    }
    const Slice again{s.file, FrameOf(*image, std::max<int64_t>(s.frame, 0)),
                      image->pixel_data ? image->pixel_data->size() : 0, 0.0, s.frame};
    absl::Status same = CheckPlaceable(again);
    if (same.ok()) same = CheckSameShape(slices.front(), again);
    if (same.ok() && s.frame >= 0 && FrameStackOf(*image) == FrameStack::kNone) {
      same = absl::DataLossError("its frames are no longer slices");
    }
    if (!same.ok()) {
      return FileError(s.file, absl::StrCat("changed while it was read: ", same.message()));
    }
    const absl::string_view pixels =
        image->pixel_data->substr(static_cast<size_t>(std::max<int64_t>(s.frame, 0)) * per_slice *
                                  static_cast<size_t>(first.bits_allocated / 8));
    const DicomImage& im = again.image;
    std::byte* out = data.data() + k * per_slice * VoxelSize(gathered);
    switch (gathered) {
      case VoxelType::kUint8:
        GatherSlice<uint8_t>(im, pixels, per_slice, out);
        break;
      case VoxelType::kInt16:
        GatherSlice<int16_t>(im, pixels, per_slice, out);
        break;
      case VoxelType::kUint16:
        GatherSlice<uint16_t>(im, pixels, per_slice, out);
        break;
      case VoxelType::kInt32:
        GatherSlice<int32_t>(im, pixels, per_slice, out);
        break;
      default:
        // Per-slice scaling is applied here (float64 holds 32-bit samples exactly).
        GatherSlice<double>(im, pixels, per_slice, out, to_float64 && scaled);
        break;
    }
  }
  VoxelType type = gathered;
  if (scaled && !to_float64) {
    absl::StatusOr<DecodedVoxels> voxels = DecodeVoxels(
        absl::string_view(reinterpret_cast<const char*>(data.data()), data.size()),
        StoredTypeOf(gathered), ByteOrder::kLittle, first.rescale_slope, first.rescale_intercept);
    if (!voxels.ok()) return WithPath(path, voxels.status());
    type = voxels->type;
    data = std::move(voxels->data);
  }
  absl::StatusOr<VolumeFile> volume = PlaceOnGrid(path, affine, dims, type, std::move(data));
  if (!volume.ok()) return volume.status();
  std::vector<std::string> skipped;
  if (not_dicom > 0) skipped.push_back(absl::StrCat(not_dicom, " files that are not DICOM"));
  if (no_image > 0) skipped.push_back(absl::StrCat(no_image, " DICOM files without an image"));
  if (duplicates > 0) {
    skipped.push_back(absl::StrCat(duplicates, " duplicate images (the same SOP Instance UID)"));
  }
  if (unreadable > 0) {
    skipped.push_back(
        absl::StrCat(unreadable, " files that could not be read (e.g. ", first_unreadable, ")"));
  }
  if (!compressed.empty()) {
    skipped.push_back(
        absl::StrCat("the compressed images of ", compressed.size(), " other series"));
  }
  if (!skipped.empty()) {
    volume->warnings.push_back(absl::StrCat(directory, ": skipped ", absl::StrJoin(skipped, ", ")));
  }
  volume->warnings.insert(volume->warnings.end(), nm_warnings.begin(), nm_warnings.end());
  return volume;
}

}  // namespace tetrefine::io
