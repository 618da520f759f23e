// libFuzzer target: the Medit (.mesh) reader on arbitrary text, then a write-read round trip of
// what Medit stores (points, tets, tet references as labels).

#include "client/io/medit_format.h"
#include "fuzz/mesh_parser_check.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  tetrefine::fuzz::CheckMeshParser({.parse = &tetrefine::io::ParseMedit,
                                    .format = &tetrefine::io::FormatMedit,
                                    .path = "fuzz.mesh",
                                    .keeps_values = false,
                                    .keeps_quality = false,
                                    .keeps_iteration = false,
                                    .keeps_label_name = false,
                                    .keeps_frame = false},
                                   data, size);
  return 0;
}
