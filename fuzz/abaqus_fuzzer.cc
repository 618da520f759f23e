// libFuzzer target: the Abaqus .inp reader on arbitrary text. There is no .inp writer, so instead
// of a round trip: a mesh read must be valid, its labels one per tet, each 0 or a named region.
// *INCLUDE is followed: the input includes itself under the name "self" (up to 64 times per
// input, which the depth limit and the nesting exercise), any other name is missing.

#include <string>

#include "absl/status/status.h"
#include "absl/strings/string_view.h"
#include "client/io/abaqus_format.h"
#include "fuzz/fuzz_support.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const absl::string_view text(reinterpret_cast<const char*>(data), size);
  int includes = 0;
  const tetrefine::io::AbaqusIncludeReader include =
      [&](absl::string_view name) -> absl::StatusOr<std::string> {
    if (name != "self" || ++includes > 64) return absl::NotFoundError("no such file");
    return std::string(text);
  };
  const absl::StatusOr<tetrefine::io::MeshFile> file =
      tetrefine::io::ParseAbaqus(text, "fuzz.inp", include);
  if (!file.ok()) {
    TETREFINE_FUZZ_CHECK(!file.status().message().empty(), "an error without a message");
    return 0;
  }
  const absl::Status valid = tetrefine::io::ValidateMeshFile(*file, "fuzz.inp");
  TETREFINE_FUZZ_CHECK(valid.ok(), valid.ToString());
  if (file->mesh.labels.empty()) {
    TETREFINE_FUZZ_CHECK(file->region_names.empty(), "region names without labels");
    return 0;
  }
  TETREFINE_FUZZ_CHECK(file->mesh.labels.size() == file->mesh.tets.size(), "labels per tet");
  for (int32_t label : file->mesh.labels) {
    TETREFINE_FUZZ_CHECK(label == 0 || file->region_names.count(label) == 1,
                         "a label without a region name");
  }
  return 0;
}
