#include "tests/io/nifti_builder.h"

#include <algorithm>
#include <cstring>

namespace tetrefine::io::iotest {
namespace {

class Writer {
 public:
  Writer(std::string& bytes, bool big_endian) : bytes_(bytes), big_endian_(big_endian) {}

  template <typename T>
  void Put(size_t offset, T value) {
    char raw[sizeof(T)];
    std::memcpy(raw, &value, sizeof(T));
    if (big_endian_) std::reverse(raw, raw + sizeof(T));
    std::memcpy(bytes_.data() + offset, raw, sizeof(T));
  }

 private:
  std::string& bytes_;
  bool big_endian_;
};

template <typename T>
std::string Samples(const std::vector<T>& values, bool big_endian) {
  std::string out(values.size() * sizeof(T), '\0');
  Writer w(out, big_endian);
  for (size_t i = 0; i < values.size(); ++i) w.Put<T>(i * sizeof(T), values[i]);
  return out;
}

}  // namespace

std::string NiftiHeaderBytes(const NiftiSpec& s) {
  const size_t header = s.version == 1 ? 348 : 540;
  const size_t total = s.pair ? header : header + 4;
  std::string h(total, '\0');
  Writer w(h, s.big_endian);
  if (s.version == 1) {
    w.Put<int32_t>(0, 348);
    for (int i = 0; i < 8; ++i) w.Put<int16_t>(40 + 2 * i, static_cast<int16_t>(s.dim[i]));
    w.Put<int16_t>(70, s.datatype);
    for (int i = 0; i < 8; ++i) w.Put<float>(76 + 4 * i, static_cast<float>(s.pixdim[i]));
    w.Put<float>(108, s.pair ? 0.0f : static_cast<float>(total));
    w.Put<float>(112, static_cast<float>(s.slope));
    w.Put<float>(116, static_cast<float>(s.inter));
    h[123] = static_cast<char>(s.xyzt_units);
    w.Put<int16_t>(252, static_cast<int16_t>(s.qform_code));
    w.Put<int16_t>(254, static_cast<int16_t>(s.sform_code));
    for (int i = 0; i < 3; ++i) w.Put<float>(256 + 4 * i, static_cast<float>(s.quatern[i]));
    for (int i = 0; i < 3; ++i) w.Put<float>(268 + 4 * i, static_cast<float>(s.qoffset[i]));
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 4; ++c)
        w.Put<float>(280 + 16 * r + 4 * c, static_cast<float>(s.srow[r][c]));
    }
    std::memcpy(h.data() + 344, s.pair ? "ni1\0" : "n+1\0", 4);
  } else {
    w.Put<int32_t>(0, 540);
    std::memcpy(h.data() + 4, s.pair ? "ni2\0\r\n\032\n" : "n+2\0\r\n\032\n", 8);
    w.Put<int16_t>(12, s.datatype);
    for (int i = 0; i < 8; ++i) w.Put<int64_t>(16 + 8 * i, s.dim[i]);
    for (int i = 0; i < 8; ++i) w.Put<double>(104 + 8 * i, s.pixdim[i]);
    w.Put<int64_t>(168, s.pair ? 0 : static_cast<int64_t>(total));
    w.Put<double>(176, s.slope);
    w.Put<double>(184, s.inter);
    w.Put<int32_t>(344, s.qform_code);
    w.Put<int32_t>(348, s.sform_code);
    for (int i = 0; i < 3; ++i) w.Put<double>(352 + 8 * i, s.quatern[i]);
    for (int i = 0; i < 3; ++i) w.Put<double>(376 + 8 * i, s.qoffset[i]);
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 4; ++c) w.Put<double>(400 + 32 * r + 8 * c, s.srow[r][c]);
    }
    w.Put<int32_t>(500, s.xyzt_units);
  }
  return h;
}

std::string FloatSamples(const std::vector<float>& values, bool big_endian) {
  return Samples(values, big_endian);
}

std::string Int16Samples(const std::vector<int16_t>& values, bool big_endian) {
  return Samples(values, big_endian);
}

}  // namespace tetrefine::io::iotest
