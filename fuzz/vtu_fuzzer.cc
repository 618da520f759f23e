// libFuzzer target: the VTK XML (.vtu) reader on arbitrary text, then a write-read round trip.

#include "client/io/vtu_format.h"
#include "fuzz/mesh_parser_check.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  tetrefine::fuzz::CheckMeshParser(
      {.parse = &tetrefine::io::ParseVtu,
       .format = [](const tetrefine::io::MeshFile& file) { return tetrefine::io::FormatVtu(file); },
       .path = "fuzz.vtu"},
      data, size);
  return 0;
}
