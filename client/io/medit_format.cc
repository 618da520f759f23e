#include "client/io/medit_format.h"

#include <limits>
#include <utility>

#include "absl/strings/ascii.h"
#include "absl/strings/str_cat.h"
#include "client/io/number_text.h"
#include "client/io/text_scanner.h"

namespace tetrefine::io {
namespace {

// Numbers per entry of the sections read only to be skipped (lower-case keyword).
int SkippedSectionWidth(const std::string& keyword) {
  static const std::pair<const char*, int> kWidths[] = {
      {"edges", 3},
      {"triangles", 4},
      {"quadrilaterals", 5},
      {"hexahedra", 9},
      {"prisms", 7},
      {"pyramids", 6},
      {"corners", 1},
      {"ridges", 1},
      {"requiredvertices", 1},
      {"requirededges", 1},
      {"requiredtriangles", 1},
      {"requiredquadrilaterals", 1},
      {"normals", 3},
      {"tangents", 3},
      {"normalatvertices", 2},
      {"tangentatedges", 3},
      {"tangentatvertices", 2},
      {"normalattrianglevertices", 3},
  };
  for (const auto& [name, width] : kWidths) {
    if (keyword == name) return width;
  }
  return 0;
}

}  // namespace

absl::StatusOr<MeshFile> ParseMedit(absl::string_view text, absl::string_view path) {
  TextScanner in(text, path, '#');
  MeshFile file;
  Mesh& mesh = file.mesh;
  bool have_vertices = false;
  bool have_tets = false;
  while (!in.AtEnd()) {
    absl::StatusOr<absl::string_view> token = in.Token("a section keyword");
    if (!token.ok()) return token.status();
    const std::string keyword = absl::AsciiStrToLower(*token);
    if (keyword == "end") break;
    if (keyword == "meshversionformatted") {
      if (absl::Status s = in.IntIn("MeshVersionFormatted", 1, 4).status(); !s.ok()) return s;
    } else if (keyword == "dimension") {
      absl::StatusOr<int64_t> dimension = in.Int("the dimension");
      if (!dimension.ok()) return dimension.status();
      if (*dimension != 3) {
        return in.Error(absl::StrCat("Dimension ", *dimension, ": only 3D meshes are read"));
      }
    } else if (keyword == "vertices") {
      if (have_vertices) return in.Error("second Vertices section");
      absl::StatusOr<int64_t> count = in.IntIn("the vertex count", 0, (int64_t{1} << 32) - 1);
      if (!count.ok()) return count.status();
      // Each vertex is at least "x y z r" with separators: 8 bytes.
      if (absl::Status s = in.CheckCount(*count, 8, "vertices"); !s.ok()) return s;
      mesh.points.resize(*count);
      for (Vec3& p : mesh.points) {
        for (double& x : p) {
          absl::StatusOr<double> value = in.FiniteDouble("a vertex coordinate");
          if (!value.ok()) return value.status();
          x = *value;
        }
        if (absl::Status s = in.Int("a vertex reference").status(); !s.ok()) return s;
      }
      have_vertices = true;
    } else if (keyword == "tetrahedra") {
      if (have_tets) return in.Error("second Tetrahedra section");
      absl::StatusOr<int64_t> count = in.Int("the tetrahedron count");
      if (!count.ok()) return count.status();
      if (absl::Status s = in.CheckCount(*count, 10, "tetrahedra"); !s.ok()) return s;
      if (!have_vertices) return in.Error("Tetrahedra before Vertices");
      const int64_t v = static_cast<int64_t>(mesh.points.size());
      mesh.tets.resize(*count);
      file.tet_iteration.resize(*count);
      for (int64_t t = 0; t < *count; ++t) {
        for (uint32_t& index : mesh.tets[t]) {
          // Medit indices are 1-based.
          absl::StatusOr<int64_t> i = in.IntIn("a tetrahedron vertex index", 1, v);
          if (!i.ok()) return i.status();
          index = static_cast<uint32_t>(*i - 1);
        }
        absl::StatusOr<int64_t> ref =
            in.IntIn("a tetrahedron reference", std::numeric_limits<int32_t>::min(),
                     std::numeric_limits<int32_t>::max());
        if (!ref.ok()) return ref.status();
        file.tet_iteration[t] = static_cast<int32_t>(*ref);
      }
      have_tets = true;
    } else if (const int width = SkippedSectionWidth(keyword); width > 0) {
      absl::StatusOr<int64_t> count = in.Int(absl::StrCat("the ", *token, " count"));
      if (!count.ok()) return count.status();
      if (absl::Status s = in.CheckCount(*count, 2 * width, *token); !s.ok()) return s;
      for (int64_t i = 0; i < *count * width; ++i) {
        if (absl::Status s = in.Double(absl::StrCat("a number of ", *token)).status(); !s.ok()) {
          return s;
        }
      }
    } else {
      return in.Error(absl::StrCat("unknown Medit section \"", token->substr(0, 40), "\""));
    }
  }
  if (!have_vertices) return in.Error("no Vertices section (not a Medit mesh?)");
  // A volume mesh without its tets is more likely cut short than meant.
  if (!have_tets) return in.Error("no Tetrahedra section (truncated, or a surface mesh?)");
  return file;
}

std::string FormatMedit(const MeshFile& file) {
  const Mesh& mesh = file.mesh;
  std::string out = "MeshVersionFormatted 2\nDimension 3\n";
  absl::StrAppend(&out, "Vertices\n", mesh.points.size(), "\n");
  for (const Vec3& p : mesh.points) {
    for (double x : p) {
      AppendDouble(out, x);
      out += ' ';
    }
    out += "0\n";
  }
  absl::StrAppend(&out, "Tetrahedra\n", mesh.tets.size(), "\n");
  for (size_t t = 0; t < mesh.tets.size(); ++t) {
    const Tet& tet = mesh.tets[t];
    absl::StrAppend(&out, tet[0] + 1, " ", tet[1] + 1, " ", tet[2] + 1, " ", tet[3] + 1, " ",
                    file.tet_iteration.empty() ? 0 : file.tet_iteration[t], "\n");
  }
  out += "End\n";
  return out;
}

}  // namespace tetrefine::io
