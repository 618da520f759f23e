#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace tetrefine::io::iotest {

// Hand-assembled NIfTI headers for tests, written field by field from the standard's layout and
// independent of client/io's writer, so reader and writer cannot share a mistake.
struct NiftiSpec {
  int version = 1;  // 1 or 2
  bool big_endian = false;
  bool pair = false;  // magic ni1/ni2 (.hdr + .img) instead of n+1/n+2
  std::array<int64_t, 8> dim{3, 2, 2, 2, 1, 1, 1, 1};
  int16_t datatype = 16;  // float32
  std::array<double, 8> pixdim{1, 1, 1, 1, 0, 0, 0, 0};
  double slope = 0.0;
  double inter = 0.0;
  int xyzt_units = 2;  // mm
  int qform_code = 0;
  int sform_code = 0;
  std::array<double, 3> quatern{};
  std::array<double, 3> qoffset{};
  std::array<std::array<double, 4>, 3> srow{};
};

// The header (plus the 4-byte extension flag for single files). For a single file append the
// samples; vox_offset is set to the returned size.
std::string NiftiHeaderBytes(const NiftiSpec& spec);

// Samples as bytes in the spec's byte order.
std::string FloatSamples(const std::vector<float>& values, bool big_endian);
std::string Int16Samples(const std::vector<int16_t>& values, bool big_endian);

}  // namespace tetrefine::io::iotest
