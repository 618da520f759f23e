#pragma once

#include "absl/status/statusor.h"
#include "client/io/volume_file.h"

namespace tetrefine::fuzz {

// What every volume reader promises for any input: an error with a message, or a volume whose
// samples are finite and which survives a NIfTI-2 write and read unchanged (grid values exactly:
// NIfTI-2 stores float64 geometry; samples bit for bit).
void CheckVolumeRead(const absl::StatusOr<io::VolumeFile>& read);

}  // namespace tetrefine::fuzz
