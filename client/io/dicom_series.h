#pragma once

#include <string>

#include "absl/status/statusor.h"
#include "client/io/volume_file.h"

namespace tetrefine::io {

// Reads a DICOM series (CT, MR, PET, SPECT slices as scanners and PACS export them) as one
// volume. `path` is either a directory, whose files (not its subdirectories) must hold one
// series, or one file of a series, which selects the files of its directory that share its
// Series Instance UID (0020,000E). Files without the DICOM magic (notes, .DS_Store), DICOM
// files without an image (a DICOMDIR, a report), second copies of an image (the same SOP
// Instance UID), compressed images of other series and files that cannot be parsed are skipped,
// and a warning counts them (a file that was a slice of the series leaves a gap, refused below).
//
// Geometry, by the DICOM formula (as ITK places a series, and dcm2niix an untilted one): the
// slices are sorted by their Image Position
// (Patient) along the normal of their common Image Orientation (Patient), never by file name or
// Instance Number. Sample (i, j, k) is column i, row j of the k-th slice, at
//   IPP_0 + i * row_direction * column_spacing + j * column_direction * row_spacing + k * step,
// step = (IPP_last - IPP_0) / (slices - 1): a gantry tilt (positions not along the normal) gives
// a sheared grid, which VolumeFile carries as its direction. DICOM's LPS is converted to RAS
// (VolumeFile's frame) by negating x and y.
//
// Values: the stored samples (Bits Stored of Bits Allocated, sign-extended when Pixel
// Representation is 1) times Rescale Slope plus Rescale Intercept, so a CT reads in Hounsfield
// units. Unscaled series keep their integer type (8-bit signed samples become int16, 32-bit
// unsigned float64); scaled ones are float32 (samples of at most 16 bits, one scaling) or
// float64.
//
// Errors name the directory or file and the attribute: several series in a directory, one
// slice, slices that differ in size, orientation or spacing, two slices at one position (a 4D or
// multi-echo series), uneven slice spacing (a missing slice), colour or multi-frame images,
// compressed transfer syntaxes (convert such series with dcm2niix or `gdcmconv --raw`).
absl::StatusOr<VolumeFile> ReadDicomSeries(const std::string& path);

// True for a path ReadVolume hands to ReadDicomSeries: a directory, a .dcm or .dicom file, or a
// file without a recognised extension that starts with the DICOM magic (scanners name slices
// "IM0001" or by their UID).
bool IsDicomPath(const std::string& path);

}  // namespace tetrefine::io
