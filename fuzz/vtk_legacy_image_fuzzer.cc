// libFuzzer target: the legacy VTK STRUCTURED_POINTS (image) reader on arbitrary bytes.

#include "absl/strings/string_view.h"
#include "client/io/vtk_legacy_format.h"
#include "fuzz/volume_reader_check.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const absl::string_view bytes(reinterpret_cast<const char*>(data), size);
  tetrefine::fuzz::CheckVolumeRead(tetrefine::io::ParseVtkLegacyImage(bytes, "input.vtk"));
  return 0;
}
