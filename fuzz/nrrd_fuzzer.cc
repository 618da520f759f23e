// libFuzzer target: the NRRD reader on arbitrary bytes written to a private .nrrd file.

#include <string>

#include "client/io/nrrd_reader.h"
#include "fuzz/fuzz_support.h"
#include "fuzz/volume_reader_check.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string_view bytes(reinterpret_cast<const char*>(data), size);
  // A detached data file outside the private directory could name a device that never ends
  // (/dev/zero): in real use that is the user's own choice of file, not something to fuzz.
  if (tetrefine::fuzz::AnyKeyLineContains(bytes, {"data file", "datafile"}, '/')) return 0;
  const std::string path = tetrefine::fuzz::WritePrivateFile("input.nrrd", bytes);
  tetrefine::fuzz::CheckVolumeRead(tetrefine::io::ReadNrrd(path));
  return 0;
}
