// libFuzzer target: the binary Medit (.meshb, libMeshb versions 1-4) reader on arbitrary bytes,
// then a write-read round trip through the version-3 writer (doubles: exact for every version
// read, version 1's floats included).

#include "client/io/medit_format.h"
#include "fuzz/mesh_parser_check.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  tetrefine::fuzz::CheckMeshParser(
      {.parse = [](absl::string_view bytes,
                   absl::string_view path) { return tetrefine::io::ParseMeshb(bytes, path); },
       .format =
           [](const tetrefine::io::MeshFile& file) { return tetrefine::io::FormatMeshb(file); },
       .path = "fuzz.meshb",
       .keeps_values = false,
       .keeps_quality = false,
       .keeps_iteration = false,
       .keeps_label_name = false,
       .keeps_frame = false},
      data, size);
  return 0;
}
