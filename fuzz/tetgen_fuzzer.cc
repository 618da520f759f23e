// libFuzzer target: the TetGen .node/.ele reader on arbitrary text, then a write-read round trip.
// One input holds both files: the .node text, a NUL byte, the .ele text.

#include <string>

#include "client/io/tetgen_format.h"
#include "fuzz/mesh_parser_check.h"

namespace {

absl::StatusOr<tetrefine::io::MeshFile> ParseBoth(absl::string_view text, absl::string_view) {
  const size_t nul = text.find('\0');
  const absl::string_view node = text.substr(0, nul);
  const absl::string_view ele =
      nul == absl::string_view::npos ? absl::string_view() : text.substr(nul + 1);
  return tetrefine::io::ParseTetgen(node, ele, "fuzz.node", "fuzz.ele");
}

std::string FormatBoth(const tetrefine::io::MeshFile& file) {
  tetrefine::io::TetgenFiles files = tetrefine::io::FormatTetgen(file);
  return files.node + '\0' + files.ele;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  tetrefine::fuzz::CheckMeshParser({.parse = &ParseBoth,
                                    .format = &FormatBoth,
                                    .path = "fuzz.ele",
                                    .keeps_values = false,
                                    .keeps_quality = false,
                                    .keeps_iteration = false},
                                   data, size);
  return 0;
}
