#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "absl/strings/string_view.h"

namespace tetrefine::io {

// What the functional groups of an enhanced multi-frame image (PS3.3 C.7.6.16) say about one
// frame (or, shared, about every frame), each where the file gives it.
struct DicomFrameGroups {
  // Plane Position Sequence (0020,9113) > Image Position (Patient) (0020,0032), LPS mm.
  std::optional<std::array<double, 3>> position;
  // Plane Orientation Sequence (0020,9116) > Image Orientation (Patient) (0020,0037).
  std::optional<std::array<double, 6>> orientation;
  // Pixel Measures Sequence (0028,9110) > Pixel Spacing (0028,0030), mm.
  std::optional<std::array<double, 2>> pixel_spacing;
  // Pixel Value Transformation Sequence (0028,9145) > Rescale Slope (0028,1053) and
  // Intercept (0028,1052).
  std::optional<double> rescale_slope;
  std::optional<double> rescale_intercept;
};

// The attributes of one DICOM Part 10 file (PS3.10: a 128-byte preamble, "DICM", the file meta
// group, then the data set) that place its image in a volume. Only the data set's top level is
// read; sequences are skipped. Geometry is in DICOM's patient frame, LPS millimetres.
struct DicomImage {
  std::string media_sop_class;     // (0002,0002); a DICOMDIR says 1.2.840.10008.1.3.10
  std::string transfer_syntax;     // (0002,0010)
  std::string series_uid;          // (0020,000E)
  std::string sop_instance_uid;    // (0008,0018): the same image exported twice has the same
  std::string modality;            // (0008,0060), for messages
  std::string series_number;       // (0020,0011), for messages: what a radiologist calls it
  std::string series_description;  // (0008,103E), for messages
  int64_t rows = 0;                // (0028,0010): samples along a column, the j axis
  int64_t columns = 0;             // (0028,0011): samples along a row, the i axis
  int samples_per_pixel = 1;       // (0028,0002)
  int64_t frames = 1;              // (0028,0008)
  int bits_allocated = 0;          // (0028,0100)
  std::optional<int> bits_stored;  // (0028,0101); absent: bits_allocated (StoredBits)
  int pixel_representation = 0;    // (0028,0103): 0 unsigned, 1 two's complement
  // (0020,0032) Image Position (Patient): the world position of the first sample, LPS mm.
  std::optional<std::array<double, 3>> position;
  // (0020,0037) Image Orientation (Patient): the unit world direction of a row (increasing
  // column index i), then of a column (increasing row index j).
  std::optional<std::array<double, 6>> orientation;
  // (0028,0030) Pixel Spacing: the distance between rows (along j), then between columns
  // (along i), mm.
  std::optional<std::array<double, 2>> pixel_spacing;
  double rescale_slope = 1.0;      // (0028,1053)
  double rescale_intercept = 0.0;  // (0028,1052)
  // What a multi-frame image without functional groups (NM, PS3.3 C.8.4) says of its frames.
  // (0028,0009) Frame Increment Pointer: the tags of the vectors that index the frames, as
  // (group << 16) | element; NM reconstructed tomography names Slice Vector (0054,0080) alone.
  std::vector<uint32_t> frame_increment_pointer;
  // (0054,0080) Slice Vector: the slice (from 1) of each frame. Shared, as frame_groups is:
  // every frame's copy (FrameOf) would otherwise copy it.
  std::shared_ptr<const std::vector<uint16_t>> slice_vector;
  // (0018,0088) Spacing Between Slices, mm, signed for NM (C.8.4.15: negative stacks the
  // slices in front of the first, against the normal); (0018,0050) Slice Thickness, mm.
  std::optional<double> spacing_between_slices;
  std::optional<double> slice_thickness;
  // (0054,0022) Detector Information Sequence: where NM images keep Image Position (Patient)
  // and Image Orientation (Patient) (those of its first item), and how many items it has.
  std::optional<std::array<double, 3>> detector_position;
  std::optional<std::array<double, 6>> detector_orientation;
  int64_t detector_items = 0;
  // The first of those NM attributes found malformed (a Frame Increment Pointer or Slice Vector
  // of the wrong length, a position that is not three numbers), without the file's name; empty
  // when none is. Refused only where the NM stacking reads them, so that other files carrying
  // them read as before.
  std::string nm_problem;
  // (7FE0,0010) Pixel Data: the stored samples, little-endian, a view into the parsed bytes.
  // Empty when the file has no image (a report, a DICOMDIR), or holds one this reader does not
  // decode (then `unsupported` says why).
  std::optional<absl::string_view> pixel_data;
  // Enhanced multi-frame images: Shared Functional Groups Sequence (5200,9229) and Per-frame
  // Functional Groups Sequence (5200,9230), one entry per item (at most `frames`); shared, so
  // that the image's copies (one per frame, FrameOf) do not copy them: that took memory
  // quadratic in the frames (9 GB for 8000 frames, found by a sweep).
  DicomFrameGroups shared_groups;
  std::shared_ptr<const std::vector<DicomFrameGroups>> frame_groups;

  // The number of per-frame group items (0 without the sequence).
  int64_t frame_group_count() const {
    return frame_groups ? static_cast<int64_t>(frame_groups->size()) : 0;
  }
  // Non-empty for an image in a compressed transfer syntax (JPEG, JPEG-LS, JPEG 2000, RLE):
  // its header was read, its pixels cannot be; the message names the syntax and the fix.
  std::string unsupported;
};

// The bits of a sample that hold its value: Bits Stored, or Bits Allocated without it.
inline int StoredBits(const DicomImage& image) {
  return image.bits_stored.value_or(image.bits_allocated);
}

// True when `bytes` (a file's first 132 bytes suffice) start like a DICOM file: a Part 10
// file (a 128-byte preamble, then "DICM"), its file meta group without the preamble, or a data
// set without file meta information that begins at group 0008, as ACR-NEMA-era archives and
// some exporters write it.
bool HasDicomMagic(absl::string_view bytes);

// A tag as DICOM writes it in text, "(0028,0009)".
std::string TagText(uint16_t group, uint16_t element);

// `bytes` from a file for a message: printable ASCII kept, every other byte escaped (\x1b),
// at most 64 bytes, so that a hostile file cannot write terminal escapes through an error.
std::string Printable(absl::string_view bytes);

// Tag of Slice Vector (0054,0080), as frame_increment_pointer holds it.
inline constexpr uint32_t kSliceVectorTag = 0x00540080;

// How the frames of a multi-frame image are placed.
enum class FrameStack {
  kNone,      // a single frame, or frames that are not the slices of one volume
  kEnhanced,  // one Per-frame Functional Groups item a frame (enhanced CT, MR, PET)
  kNmSlices,  // Frame Increment Pointer names Slice Vector alone (NM reconstructed tomography)
};
FrameStack FrameStackOf(const DicomImage& image);

// Where the frames of a kNmSlices image go: the slice spacing that stacks them (Spacing Between
// Slices, else Slice Thickness, which dcm2niix also falls back to), and which of the two it is.
struct NmStacking {
  std::optional<double> spacing;  // mm along the normal (row x column); absent: neither given
  bool from_thickness = false;
};
NmStacking NmStackingOf(const DicomImage& image);

// Frame `frame` (0-based) of a multi-frame `image` as a single-frame image: position,
// orientation, pixel spacing and rescaling from its per-frame functional groups, else the
// shared ones, else the image's own; no functional groups, no pixel data (`frames` stays the
// file's). For a kNmSlices image, its Detector Information Sequence's position and orientation
// (else the image's own), the position moved along the normal to the frame's slice (its Slice
// Vector value, else its frame order) by NmStackingOf's spacing. For a single-frame image
// (frame 0), the image itself without its pixel data.
DicomImage FrameOf(const DicomImage& image, int64_t frame);

// Parses a DICOM file held in `bytes` (which the result's pixel_data points into): Part 10, or
// one of the forms without the preamble that HasDicomMagic accepts; without file meta, the
// transfer syntax is little endian, explicit VR when the first element has a value
// representation, else implicit. Reads the uncompressed little-endian transfer syntaxes
// (implicit and explicit VR: what scanners and PACS export by default). For the compressed ones
// (JPEG family, JPEG-LS, JPEG 2000, RLE) the header is read and `unsupported` set; any other syntax
// (big endian, deflated) is an error naming it and how to convert the file. Errors name `path` and
// the element (gggg,eeee) where the data set is malformed or truncated. Never reads outside
// `bytes`; sequences nest at most 32 deep. A value of length zero (as anonymisers leave Rescale
// Slope and Intercept) counts as absent.
absl::StatusOr<DicomImage> ParseDicomFile(absl::string_view bytes, absl::string_view path);

}  // namespace tetrefine::io
