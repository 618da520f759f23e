#include "client/io/label_names.h"

#include "absl/strings/match.h"

namespace tetrefine::io {

int LabelNameRank(absl::string_view name) {
  // Last, "cell_scalars": TetGen's `-k` writes its region attributes (`-A`) into the legacy
  // .vtk under that name, and nothing else a mesh tool writes uses it for a per-tet integer.
  static constexpr const char* kNames[] = {
      "gmsh:physical", "medit:ref", "tetgen:ref",   "CellEntityIds", "region",
      "regions",       "labels",    "label",        "MaterialIds",   "material",
      "materials",     "subdomain", "cell_scalars",
  };
  for (int i = 0; i < static_cast<int>(sizeof(kNames) / sizeof(kNames[0])); ++i) {
    if (absl::EqualsIgnoreCase(name, kNames[i])) return i;
  }
  return -1;
}

}  // namespace tetrefine::io
