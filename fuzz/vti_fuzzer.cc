// libFuzzer target: the VTK XML image (.vti) reader on arbitrary text.

#include <string>

#include "absl/strings/string_view.h"
#include "client/io/vti_reader.h"
#include "fuzz/volume_reader_check.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  tetrefine::fuzz::CheckVolumeRead(
      tetrefine::io::ParseVti(absl::string_view(text.data(), text.size()), "input.vti"));
  return 0;
}
