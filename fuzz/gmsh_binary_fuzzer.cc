// libFuzzer target: the Gmsh reader on arbitrary bytes (seeded with binary 2.2 and 4.1 files as
// `gmsh -bin` and meshio write them), then a round trip through the binary 4.1 writer.

#include "client/io/gmsh_format.h"
#include "fuzz/mesh_parser_check.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  tetrefine::fuzz::CheckMeshParser(
      {.parse = [](absl::string_view text,
                   absl::string_view path) { return tetrefine::io::ParseGmsh(text, path); },
       .format =
           [](const tetrefine::io::MeshFile& file) {
             return tetrefine::io::FormatGmsh41(file, {.binary = true});
           },
       .path = "fuzz.msh",
       .keeps_label_name = false,
       .keeps_frame = false,
       .groups_tets_by_label = true},
      data, size);
  return 0;
}
