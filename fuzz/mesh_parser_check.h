#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

#include "absl/status/statusor.h"
#include "absl/strings/string_view.h"
#include "client/io/mesh_file.h"

namespace tetrefine::fuzz {

struct MeshFormatUnderTest {
  absl::StatusOr<io::MeshFile> (*parse)(absl::string_view text, absl::string_view path);
  std::string (*format)(const io::MeshFile& file);
  const char* path;  // the name error messages carry, e.g. "fuzz.vtu"
  // What the format stores (Medit keeps neither values, quality nor iteration; Gmsh and Medit
  // store labels in their own slot, whatever the input called them, and no frame tag).
  bool keeps_values = true;
  bool keeps_quality = true;
  bool keeps_iteration = true;
  bool keeps_label_name = true;
  bool keeps_frame = true;
  // Gmsh: the tets come back grouped by label, ascending, each group in tet order.
  bool groups_tets_by_label = false;
};

// Parses `data` as the format. Any input may fail, but none may crash; an input that parses and
// passes ValidateMeshFile must survive format-then-parse unchanged (bit for bit: numbers are
// written in shortest round-trip form).
void CheckMeshParser(const MeshFormatUnderTest& format, const uint8_t* data, size_t size);

}  // namespace tetrefine::fuzz
