#include "fuzz/volume_reader_check.h"

#include <cmath>

#include "absl/strings/str_cat.h"
#include "client/io/nifti_reader.h"
#include "client/io/nifti_writer.h"
#include "fuzz/fuzz_support.h"

namespace tetrefine::fuzz {
namespace {

// Equal values (so -0.0 == 0.0: placing a grid adds +0.0 to the origin, which drops the sign).
bool Same(const Vec3& a, const Vec3& b) { return a[0] == b[0] && a[1] == b[1] && a[2] == b[2]; }

}  // namespace

void CheckVolumeRead(const absl::StatusOr<io::VolumeFile>& read) {
  if (!read.ok()) {
    TETREFINE_FUZZ_CHECK(!read.status().message().empty(), "an error without a message");
    return;
  }
  const Volume& volume = read->volume;
  const GridGeometry& grid = volume.grid();
  TETREFINE_FUZZ_CHECK(
      volume.data().size() == static_cast<size_t>(volume.voxel_count()) * VoxelSize(volume.type()),
      "data size does not match the grid");
  const Vec3 centre{0.5 * static_cast<double>(grid.dims[0] - 1),
                    0.5 * static_cast<double>(grid.dims[1] - 1),
                    0.5 * static_cast<double>(grid.dims[2] - 1)};
  TETREFINE_FUZZ_CHECK(std::isfinite(volume.SampleIndex(centre)), "non-finite sample");

  const std::string path = WritePrivateFile("roundtrip.nii", "");
  const absl::Status written = io::WriteNifti(path, volume, {.version = 2});
  TETREFINE_FUZZ_CHECK(written.ok(), written.ToString());
  absl::StatusOr<io::VolumeFile> again = io::ReadNifti(path);
  TETREFINE_FUZZ_CHECK(again.ok(), again.status().ToString());
  const Volume& back = again->volume;
  TETREFINE_FUZZ_CHECK(back.grid().dims == grid.dims, "dims changed in a NIfTI-2 round trip");
  TETREFINE_FUZZ_CHECK(
      Same(back.grid().spacing, grid.spacing),
      absl::StrCat("spacing changed in a NIfTI-2 round trip: ", grid.spacing[0], " ",
                   grid.spacing[1], " ", grid.spacing[2], " -> ", back.grid().spacing[0], " ",
                   back.grid().spacing[1], " ", back.grid().spacing[2]));
  TETREFINE_FUZZ_CHECK(Same(back.grid().origin, grid.origin),
                       "origin changed in a NIfTI-2 round trip");
  TETREFINE_FUZZ_CHECK(back.type() == volume.type(), "voxel type changed in a round trip");
  TETREFINE_FUZZ_CHECK(back.data() == volume.data(), "samples changed in a NIfTI-2 round trip");
}

}  // namespace tetrefine::fuzz
