#pragma once

#include <string>

#include "absl/status/status.h"
#include "core/volume.h"

namespace tetrefine::io {

struct NiftiWriteOptions {
  // 1: NIfTI-1 (float32 geometry, what every tool reads); 2: NIfTI-2 (float64 geometry).
  int version = 1;
};

// Writes `volume` as a single-file NIfTI (.nii, or gzipped when `path` ends in .nii.gz), in
// little-endian order and the volume's own sample type. The geometry goes into both sform and
// qform (code 1, scanner) as the diagonal affine diag(spacing) + origin in RAS mm, so reading it
// back gives the same grid. A slab is written as the sub-grid it covers. NIfTI-1 stores the
// geometry as float32, so origin and spacing round to float there. The file is written through a
// temporary file and renamed into place.
absl::Status WriteNifti(const std::string& path, const Volume& volume,
                        const NiftiWriteOptions& options = {});

}  // namespace tetrefine::io
