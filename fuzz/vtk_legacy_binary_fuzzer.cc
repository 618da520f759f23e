// libFuzzer target: the legacy VTK reader on arbitrary bytes (seeded with BINARY files, 4.2 and
// 5.1, as VTK 9, meshio and 3D Slicer write them), then a round trip through the binary writer.

#include "client/io/vtk_legacy_format.h"
#include "fuzz/mesh_parser_check.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  tetrefine::fuzz::CheckMeshParser({.parse = &tetrefine::io::ParseVtkLegacy,
                                    .format =
                                        [](const tetrefine::io::MeshFile& file) {
                                          return tetrefine::io::FormatVtkLegacy(file,
                                                                                {.binary = true});
                                        },
                                    .path = "fuzz.vtk"},
                                   data, size);
  return 0;
}
