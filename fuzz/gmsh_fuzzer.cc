// libFuzzer target: the Gmsh (.msh 2.2 and 4.1) reader on arbitrary text, then a write-read round
// trip through the 4.1 writer.

#include "client/io/gmsh_format.h"
#include "fuzz/mesh_parser_check.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  tetrefine::fuzz::CheckMeshParser(
      {.parse = [](absl::string_view text,
                   absl::string_view path) { return tetrefine::io::ParseGmsh(text, path); },
       .format = &tetrefine::io::FormatGmsh41,
       .path = "fuzz.msh"},
      data, size);
  return 0;
}
