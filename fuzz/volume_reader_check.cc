#include "fuzz/volume_reader_check.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "absl/strings/str_cat.h"
#include "client/io/nifti_reader.h"
#include "client/io/nifti_writer.h"
#include "fuzz/fuzz_support.h"

namespace tetrefine::fuzz {
namespace {

// Equal values (so -0.0 == 0.0: placing a grid adds +0.0 to the origin, which drops the sign).
bool Same(const Vec3& a, const Vec3& b) { return a[0] == b[0] && a[1] == b[1] && a[2] == b[2]; }

// Equal within `ulps` units in the last place of the larger magnitude.
bool Near(double a, double b, double ulps) {
  return std::abs(a - b) <=
         ulps * std::numeric_limits<double>::epsilon() * std::max(std::abs(a), std::abs(b));
}

// An oblique grid is stored as the sform columns direction * spacing and read back as their
// lengths and unit directions: each step rounds, so spacing and direction come back within a few
// ulps, not to the bit (a sheared .vti Direction found it: 5.40833 came back 1 ulp off). An
// axis-aligned grid stores its spacing itself and must come back exactly.
bool SameGeometry(const GridGeometry& a, const GridGeometry& b) {
  if (IsIdentityDirection(a.direction)) {
    return Same(a.spacing, b.spacing) && IsIdentityDirection(b.direction);
  }
  for (int i = 0; i < 3; ++i) {
    if (!Near(a.spacing[i], b.spacing[i], 4)) return false;
  }
  for (int i = 0; i < 9; ++i) {
    if (std::abs(a.direction[i] - b.direction[i]) > 8 * std::numeric_limits<double>::epsilon()) {
      return false;
    }
  }
  return true;
}

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
      SameGeometry(grid, back.grid()),
      absl::StrCat("spacing or direction changed in a NIfTI-2 round trip: ", grid.spacing[0], " ",
                   grid.spacing[1], " ", grid.spacing[2], " -> ", back.grid().spacing[0], " ",
                   back.grid().spacing[1], " ", back.grid().spacing[2]));
  TETREFINE_FUZZ_CHECK(Same(back.grid().origin, grid.origin),
                       "origin changed in a NIfTI-2 round trip");
  TETREFINE_FUZZ_CHECK(back.type() == volume.type(), "voxel type changed in a round trip");
  TETREFINE_FUZZ_CHECK(back.data() == volume.data(), "samples changed in a NIfTI-2 round trip");
}

}  // namespace tetrefine::fuzz
