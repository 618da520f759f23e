// libFuzzer target: the legacy VTK (.vtk) reader on arbitrary text, then a write-read round trip.

#include "client/io/vtk_legacy_format.h"
#include "fuzz/mesh_parser_check.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  tetrefine::fuzz::CheckMeshParser(
      {.parse = &tetrefine::io::ParseVtkLegacy,
       .format =
           [](const tetrefine::io::MeshFile& file) { return tetrefine::io::FormatVtkLegacy(file); },
       .path = "fuzz.vtk"},
      data, size);
  return 0;
}
