#pragma once

#include <cstdint>
#include <vector>

#include "absl/status/status.h"
#include "absl/strings/string_view.h"
#include "core/mesh.h"

namespace tetrefine::io {

// A tetrahedral mesh as stored in a file: the core Mesh plus optional per-tet arrays.
//   mesh.points:   V x 3 world coordinates (mm for imaging data).
//   mesh.tets:     T x 4 zero-based vertex indices.
//   mesh.values:   V scalars, or empty when the file has no "value" point data.
//   tet_iteration: T integers (the refinement iteration that created each tet), or empty.
//   tet_quality:   T quality measures, or empty.
struct MeshFile {
  tetrefine::Mesh mesh;
  std::vector<int32_t> tet_iteration;
  std::vector<float> tet_quality;
};

// OK when every array has its documented length (or is empty where allowed), every index is
// below V (and V fits uint32), and every coordinate, value and quality is finite. The message
// starts with `path` and names the first offending entry.
absl::Status ValidateMeshFile(const MeshFile& file, absl::string_view path);

}  // namespace tetrefine::io
