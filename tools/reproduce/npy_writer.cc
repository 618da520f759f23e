#include "tools/reproduce/npy_writer.h"

#include <cstdint>
#include <cstring>

#include "absl/strings/str_cat.h"

namespace tetrefine::reproduce {

std::string VolumeNpy(const Volume& volume) {
  const Index3& lo = volume.lo();
  const Index3& hi = volume.hi();
  const int64_t nx = hi[0] - lo[0], ny = hi[1] - lo[1], nz = hi[2] - lo[2];
  // The format: magic, version 1.0, a little-endian uint16 header length, then a Python dict
  // literal padded with spaces and ended by a newline so that the data starts at a multiple of 64.
  std::string header = absl::StrCat("{'descr': '<f8', 'fortran_order': False, 'shape': (", nz, ", ",
                                    ny, ", ", nx, "), }");
  constexpr size_t kPreamble = 10;  // magic (6) + version (2) + header length (2)
  const size_t total = (kPreamble + header.size() + 1 + 63) / 64 * 64;
  header.append(total - kPreamble - header.size() - 1, ' ');
  header += '\n';
  std::string out("\x93NUMPY\x01\x00", 8);
  out += static_cast<char>(header.size() & 0xff);
  out += static_cast<char>(header.size() >> 8);
  out += header;
  out.reserve(out.size() + static_cast<size_t>(nx * ny * nz) * sizeof(double));
  for (int64_t k = lo[2]; k < hi[2]; ++k) {
    for (int64_t j = lo[1]; j < hi[1]; ++j) {
      for (int64_t i = lo[0]; i < hi[0]; ++i) {
        const double v = volume.At(i, j, k);
        char bytes[sizeof v];
        std::memcpy(bytes, &v, sizeof v);  // little-endian host (core/volume.cc asserts it)
        out.append(bytes, sizeof v);
      }
    }
  }
  return out;
}

}  // namespace tetrefine::reproduce
