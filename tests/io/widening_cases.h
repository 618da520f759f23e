#pragma once

#include <optional>
#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "client/io/volume_file.h"
#include "client/io/voxel_decode.h"

namespace tetrefine::io::iotest {

// A 2 x 2 x 2 volume of a stored type a Volume lacks (int8, uint32, int64, uint64), with values
// at the edges of what widens exactly (as the Python client widens numpy arrays): each reader
// must read it sample for sample or refuse it naming the largest magnitude.
struct WideningCase {
  std::string label;
  StoredType stored;
  std::vector<std::string> values;   // 8 decimal integers, x fastest
  std::optional<VoxelType> read_as;  // nullopt: refused
  std::string magnitude;             // refused: the largest magnitude the error names
};

std::vector<WideningCase> WideningCases();

// The values as stored, each StoredSize(stored) bytes in the given byte order.
std::string WideningBytes(const WideningCase& c, bool big_endian);

// The values as decimal text, separated by `separator`.
std::string WideningText(const WideningCase& c, const std::string& separator = " ");

// Checks a read of the case's file `path`: the type and every sample (file voxel (i, j, k) at
// the world point file.affine maps it to) equal to the stored integer, or the refusal naming
// the file, the stored type and the magnitude.
void ExpectWidened(const WideningCase& c, const absl::StatusOr<VolumeFile>& file,
                   const std::string& path);

}  // namespace tetrefine::io::iotest
