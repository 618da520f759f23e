#include "client/io/medit_format.h"

#include <limits>
#include <utility>
#include <vector>

#include "absl/strings/ascii.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_split.h"
#include "client/io/cell_census.h"
#include "client/io/number_text.h"
#include "client/io/text_scanner.h"

namespace tetrefine::io {
namespace {

// A Medit element section that is not a tetrahedron: numbers per entry, and what it is.
struct OtherSection {
  const char* keyword;  // lower-case
  int width;            // numbers per entry (vertex indices and the reference)
  CellKind kind;
};

const OtherSection* FindOtherSection(const std::string& keyword) {
  const auto skip = [](const char* singular, const char* plural) {
    return CellKind{singular, plural, CellFate::kSkip};
  };
  const auto volume = [](const char* singular, const char* plural) {
    return CellKind{singular, plural, CellFate::kUnsupported};
  };
  static const OtherSection kSections[] = {
      {"edges", 3, skip("edge", "edges")},
      {"triangles", 4, skip("triangle", "triangles")},
      {"quadrilaterals", 5, skip("quadrilateral", "quadrilaterals")},
      {"edgesp2", 4, skip("edge", "edges")},
      {"trianglesp2", 7, skip("triangle", "triangles")},
      {"quadrilateralsq2", 10, skip("quadrilateral", "quadrilaterals")},
      {"hexahedra", 9, volume("hexahedron", "hexahedra")},
      {"hexaedra", 9, volume("hexahedron", "hexahedra")},  // Dobrzynski's spelling
      {"prisms", 7, volume("prism", "prisms")},
      {"pyramids", 6, volume("pyramid", "pyramids")},
      {"tetrahedrap2", 11, volume("second-order tetrahedron", "second-order tetrahedra")},
      {"hexahedraq2", 28, volume("second-order hexahedron", "second-order hexahedra")},
  };
  for (const OtherSection& s : kSections) {
    if (keyword == s.keyword) return &s;
  }
  return nullptr;
}

// Numbers per entry of the non-element sections read only to be skipped (lower-case keyword).
int SkippedSectionWidth(const std::string& keyword) {
  static const std::pair<const char*, int> kWidths[] = {
      {"corners", 1},           {"ridges", 1},
      {"requiredvertices", 1},  {"requirededges", 1},
      {"requiredtriangles", 1}, {"requiredquadrilaterals", 1},
      {"normals", 3},           {"tangents", 3},
      {"normalatvertices", 2},  {"tangentatedges", 3},
      {"tangentatvertices", 2}, {"normalattrianglevertices", 3},
  };
  for (const auto& [name, width] : kWidths) {
    if (keyword == name) return width;
  }
  return 0;
}

absl::Status SkipNumbers(TextScanner& in, int64_t count, int width, absl::string_view what) {
  if (absl::Status s = in.CheckCount(count, 2 * width, what); !s.ok()) return s;
  for (int64_t i = 0; i < count * width; ++i) {
    if (absl::Status s = in.Double(absl::StrCat("a number of ", what)).status(); !s.ok()) {
      return s;
    }
  }
  return absl::OkStatus();
}

}  // namespace

absl::StatusOr<MeshFile> ParseMedit(absl::string_view text, absl::string_view path) {
  TextScanner in(text, path, '#');
  MeshFile file;
  Mesh& mesh = file.mesh;
  bool have_vertices = false;
  bool have_tets = false;
  CellCensus census;
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
      // Several Tetrahedra sections append (meshio writes one per cell block).
      absl::StatusOr<int64_t> count = in.Int("the tetrahedron count");
      if (!count.ok()) return count.status();
      if (absl::Status s = in.CheckCount(*count, 10, "tetrahedra"); !s.ok()) return s;
      if (!have_vertices) return in.Error("Tetrahedra before Vertices");
      const int64_t v = static_cast<int64_t>(mesh.points.size());
      const size_t first = mesh.tets.size();
      mesh.tets.resize(first + *count);
      file.mesh.labels.resize(first + *count);
      for (size_t t = first; t < mesh.tets.size(); ++t) {
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
        file.mesh.labels[t] = static_cast<int32_t>(*ref);
        // Gmsh writes quadratic tets under "Tetrahedra", ten nodes and a reference per line;
        // read five at a time they misparse, and the error came much later as an "unknown Medit
        // section" (found by a file-format sweep). The format does not require a line per tet,
        // so only a first line whose count of numbers is not a multiple of five is refused.
        if (t == first) {
          const std::vector<absl::string_view> extra =
              absl::StrSplit(in.PeekRestOfLine(), absl::ByAnyChar(" \t"), absl::SkipEmpty());
          const int64_t numbers = 5 + static_cast<int64_t>(extra.size());
          if (numbers % 5 != 0) {
            return in.Error(absl::StrCat(
                "a Tetrahedra line holds ", numbers,
                " numbers, not 5 (4 vertex indices and a reference)",
                numbers == 11 ? ": quadratic (10-node) tets, which tetrefine does not read" : ""));
          }
        }
      }
      have_tets = true;
    } else if (const OtherSection* other = FindOtherSection(keyword)) {
      absl::StatusOr<int64_t> count = in.Int(absl::StrCat("the ", *token, " count"));
      if (!count.ok()) return count.status();
      if (absl::Status s = SkipNumbers(in, *count, other->width, *token); !s.ok()) return s;
      census.Add(other->kind, *count);
    } else if (const int width = SkippedSectionWidth(keyword); width > 0) {
      absl::StatusOr<int64_t> count = in.Int(absl::StrCat("the ", *token, " count"));
      if (!count.ok()) return count.status();
      if (absl::Status s = SkipNumbers(in, *count, width, *token); !s.ok()) return s;
    } else {
      return in.Error(absl::StrCat("unknown Medit section ", QuoteToken(*token)));
    }
  }
  if (!have_vertices) return in.Error("no Vertices section (not a Medit mesh?)");
  census.AddTets(static_cast<int64_t>(mesh.tets.size()));
  if (absl::Status s = census.Check(path); !s.ok()) return s;
  file.skipped_cells = census.SkippedCells();
  // A volume mesh without its tets is more likely cut short than meant.
  if (!have_tets) return in.Error("no Tetrahedra section (truncated, or a surface mesh?)");
  file.label_name = "medit:ref";
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
                    file.mesh.labels.empty() ? 0 : file.mesh.labels[t], "\n");
  }
  out += "End\n";
  return out;
}

}  // namespace tetrefine::io
