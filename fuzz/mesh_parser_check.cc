#include "fuzz/mesh_parser_check.h"

#include <algorithm>
#include <cstring>
#include <vector>

#include "absl/strings/str_cat.h"
#include "client/io/gmsh_format.h"
#include "fuzz/fuzz_support.h"

namespace tetrefine::fuzz {
namespace {

template <typename T>
bool SameBits(const std::vector<T>& a, const std::vector<T>& b) {
  return a.size() == b.size() &&
         (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(T)) == 0);
}

}  // namespace

void CheckMeshParser(const MeshFormatUnderTest& format, const uint8_t* data, size_t size) {
  const absl::string_view text(reinterpret_cast<const char*>(data), size);
  absl::StatusOr<io::MeshFile> file = format.parse(text, format.path);
  if (!file.ok()) {
    TETREFINE_FUZZ_CHECK(!file.status().message().empty(), "an error without a message");
    return;
  }
  if (!io::ValidateMeshFile(*file, format.path).ok()) return;

  // What the round trip must give back: the tets in the order the format writes them.
  if (format.groups_tets_by_label) io::OrderTetsAsGmshWrites(*file);
  const std::string written = format.format(*file);
  absl::StatusOr<io::MeshFile> again = format.parse(written, format.path);
  TETREFINE_FUZZ_CHECK(
      again.ok(), absl::StrCat("re-reading what was written fails: ", again.status().ToString(),
                               "\n--- written:\n", written.substr(0, 4000)));
  const Mesh& a = file->mesh;
  const Mesh& b = again->mesh;
  TETREFINE_FUZZ_CHECK(SameBits(a.points, b.points), "points changed in a round trip");
  TETREFINE_FUZZ_CHECK(SameBits(a.tets, b.tets), "tets changed in a round trip");
  if (format.keeps_values) {
    TETREFINE_FUZZ_CHECK(SameBits(a.values, b.values), "values changed in a round trip");
  }
  if (format.keeps_quality) {
    TETREFINE_FUZZ_CHECK(SameBits(file->tet_quality, again->tet_quality),
                         "tet_quality changed in a round trip");
  }
  if (format.keeps_iteration) {
    TETREFINE_FUZZ_CHECK(SameBits(file->tet_iteration, again->tet_iteration),
                         "tet_iteration changed in a round trip");
  }
  // No labels and all-zero labels are the same to Medit (every tet has a reference, 0 when
  // none) and Gmsh (0 = no physical group, or group 0).
  if (!file->mesh.labels.empty()) {
    const std::vector<int32_t>& expected = file->mesh.labels;
    const bool all_zero =
        std::all_of(expected.begin(), expected.end(), [](int32_t x) { return x == 0; });
    if (!(all_zero && again->mesh.labels.empty())) {
      TETREFINE_FUZZ_CHECK(SameBits(expected, again->mesh.labels),
                           "mesh.labels changed in a round trip");
    }
    if (format.keeps_label_name) {
      TETREFINE_FUZZ_CHECK(file->label_name == again->label_name,
                           "label_name changed in a round trip");
    }
  }
  if (format.keeps_frame) {
    TETREFINE_FUZZ_CHECK(file->frame == again->frame, "frame changed in a round trip");
  }
}

}  // namespace tetrefine::fuzz
