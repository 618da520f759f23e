#include "client/io/vtk_legacy_format.h"

#include <utility>
#include <vector>

#include "absl/strings/ascii.h"
#include "absl/strings/match.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/strip.h"
#include "client/io/number_text.h"
#include "client/io/text_scanner.h"
#include "client/io/vtk_cells.h"

namespace tetrefine::io {
namespace {

constexpr int64_t kMaxCount = int64_t{1} << 40;

// Reads `count` numbers into `out` (after checking the file can hold them).
absl::Status ReadNumbers(TextScanner& in, int64_t count, absl::string_view what,
                         std::vector<double>& out) {
  if (absl::Status s = in.CheckCount(count, 2, what); !s.ok()) return s;
  out.resize(count);
  for (double& x : out) {
    absl::StatusOr<double> value = in.Double(what);
    if (!value.ok()) return value.status();
    x = *value;
  }
  return absl::OkStatus();
}

absl::Status ReadInts(TextScanner& in, int64_t count, absl::string_view what,
                      std::vector<int64_t>& out) {
  if (absl::Status s = in.CheckCount(count, 2, what); !s.ok()) return s;
  out.resize(count);
  for (int64_t& x : out) {
    absl::StatusOr<int64_t> value = in.Int(what);
    if (!value.ok()) return value.status();
    x = *value;
  }
  return absl::OkStatus();
}

absl::Status SkipNumbers(TextScanner& in, int64_t count, absl::string_view what) {
  if (absl::Status s = in.CheckCount(count, 2, what); !s.ok()) return s;
  for (int64_t i = 0; i < count; ++i) {
    if (absl::Status s = in.Double(what).status(); !s.ok()) return s;
  }
  return absl::OkStatus();
}

// State of a parse: the arrays found so far.
struct Parsed {
  int major_version = 0;
  bool have_points = false;
  bool have_cells = false;
  bool have_types = false;
  std::vector<double> points;
  VtkCells cells;
  std::vector<double> values;
  VtkCellData cell_data;
};

// Where a named array of the current attribute section goes, or nullptr to skip it.
std::vector<double>* Destination(Parsed& p, bool point_section, absl::string_view name) {
  if (point_section) return name == "value" ? &p.values : nullptr;
  if (name == "iteration") return &p.cell_data.iteration;
  if (name == "quality") return &p.cell_data.quality;
  return nullptr;
}

absl::Status ReadCells(TextScanner& in, Parsed& p) {
  absl::StatusOr<int64_t> first = in.IntIn("the CELLS count", 0, kMaxCount);
  if (!first.ok()) return first.status();
  absl::StatusOr<int64_t> second = in.IntIn("the CELLS size", 0, kMaxCount);
  if (!second.ok()) return second.status();
  if (p.major_version >= 5) {
    // "CELLS <offsets> <connectivity>" then "OFFSETS <type>" and "CONNECTIVITY <type>".
    if (!in.ConsumeIf("OFFSETS")) return in.Error("expected OFFSETS after CELLS (version 5)");
    if (absl::Status s = in.Token("the OFFSETS type").status(); !s.ok()) return s;
    if (absl::Status s = ReadInts(in, *first, "cell offsets", p.cells.offsets); !s.ok()) return s;
    if (!in.ConsumeIf("CONNECTIVITY")) return in.Error("expected CONNECTIVITY after OFFSETS");
    if (absl::Status s = in.Token("the CONNECTIVITY type").status(); !s.ok()) return s;
    return ReadInts(in, *second, "cell connectivity", p.cells.connectivity);
  }
  // "CELLS <n> <size>" then n lines "k i_1 ... i_k".
  if (absl::Status s = in.CheckCount(*second, 2, "cell entries"); !s.ok()) return s;
  if (*first > *second) return in.Error("CELLS count exceeds its size");
  p.cells.offsets.assign(1, 0);
  p.cells.offsets.reserve(*first + 1);
  p.cells.connectivity.reserve(*second - *first);
  for (int64_t c = 0; c < *first; ++c) {
    absl::StatusOr<int64_t> k = in.IntIn("a cell's point count", 0, *second);
    if (!k.ok()) return k.status();
    for (int64_t i = 0; i < *k; ++i) {
      absl::StatusOr<int64_t> index = in.Int("a cell point index");
      if (!index.ok()) return index.status();
      p.cells.connectivity.push_back(*index);
    }
    p.cells.offsets.push_back(static_cast<int64_t>(p.cells.connectivity.size()));
  }
  if (static_cast<int64_t>(p.cells.connectivity.size()) + *first != *second) {
    return in.Error(absl::StrCat("CELLS size ", *second, " does not match the ",
                                 p.cells.connectivity.size() + *first, " numbers read"));
  }
  return absl::OkStatus();
}

// One attribute (SCALARS, FIELD, VECTORS, ...) of a POINT_DATA/CELL_DATA section of `n` tuples.
absl::Status ReadAttribute(TextScanner& in, Parsed& p, const std::string& keyword, int64_t n,
                           bool point_section) {
  if (keyword == "scalars") {
    absl::StatusOr<absl::string_view> name = in.Token("the SCALARS name");
    if (!name.ok()) return name.status();
    if (absl::Status s = in.Token("the SCALARS type").status(); !s.ok()) return s;
    // The component count is optional; the next token is then LOOKUP_TABLE or a number.
    int64_t components = 1;
    const absl::string_view rest = absl::StripAsciiWhitespace(in.RestOfLine());
    if (!rest.empty() && !ParseInt64(rest, components)) {
      return in.Error(absl::StrCat("bad SCALARS component count \"", rest.substr(0, 20), "\""));
    }
    if (components < 1 || components > 4) return in.Error("SCALARS needs 1 to 4 components");
    if (in.ConsumeIf("LOOKUP_TABLE")) {
      if (absl::Status s = in.Token("the lookup table name").status(); !s.ok()) return s;
    }
    std::vector<double>* out = Destination(p, point_section, *name);
    if (out == nullptr || components != 1) return SkipNumbers(in, n * components, *name);
    return ReadNumbers(in, n, *name, *out);
  }
  if (keyword == "field") {
    if (absl::Status s = in.Token("the FIELD name").status(); !s.ok()) return s;
    absl::StatusOr<int64_t> arrays = in.IntIn("the FIELD array count", 0, 1 << 20);
    if (!arrays.ok()) return arrays.status();
    for (int64_t a = 0; a < *arrays; ++a) {
      absl::StatusOr<absl::string_view> name = in.Token("a FIELD array name");
      if (!name.ok()) return name.status();
      absl::StatusOr<int64_t> components = in.IntIn("a FIELD component count", 1, 1 << 20);
      if (!components.ok()) return components.status();
      absl::StatusOr<int64_t> tuples = in.IntIn("a FIELD tuple count", 0, kMaxCount);
      if (!tuples.ok()) return tuples.status();
      if (absl::Status s = in.Token("a FIELD array type").status(); !s.ok()) return s;
      std::vector<double>* out = Destination(p, point_section, *name);
      if (out != nullptr && *components == 1) {
        if (*tuples != n) {
          return in.Error(
              absl::StrCat("array \"", *name, "\" has ", *tuples, " tuples, expected ", n));
        }
        if (absl::Status s = ReadNumbers(in, n, *name, *out); !s.ok()) return s;
      } else if (absl::Status s = SkipNumbers(in, *components * *tuples, *name); !s.ok()) {
        return s;
      }
      if (in.ConsumeIf("METADATA")) {
        while (!in.AtEnd() && !absl::StripAsciiWhitespace(in.RestOfLine()).empty()) {
        }
      }
    }
    return absl::OkStatus();
  }
  // Attributes kept only to be skipped: numbers per tuple.
  int64_t width = 0;
  if (keyword == "vectors" || keyword == "normals") width = 3;
  if (keyword == "tensors") width = 9;
  if (keyword == "tensors6") width = 6;
  if (width > 0) {
    for (const char* what : {"the attribute name", "the attribute type"}) {
      if (absl::Status s = in.Token(what).status(); !s.ok()) return s;
    }
    return SkipNumbers(in, n * width, keyword);
  }
  if (keyword == "texture_coordinates" || keyword == "color_scalars") {
    if (absl::Status s = in.Token("the attribute name").status(); !s.ok()) return s;
    absl::StatusOr<int64_t> dim = in.IntIn("the attribute width", 1, 16);
    if (!dim.ok()) return dim.status();
    if (keyword == "texture_coordinates") {
      if (absl::Status s = in.Token("the attribute type").status(); !s.ok()) return s;
    }
    return SkipNumbers(in, n * *dim, keyword);
  }
  if (keyword == "lookup_table") {
    if (absl::Status s = in.Token("the lookup table name").status(); !s.ok()) return s;
    absl::StatusOr<int64_t> size = in.IntIn("the lookup table size", 0, kMaxCount);
    if (!size.ok()) return size.status();
    return SkipNumbers(in, 4 * *size, "lookup table");
  }
  if (keyword == "metadata") {
    while (!in.AtEnd() && !absl::StripAsciiWhitespace(in.RestOfLine()).empty()) {
    }
    return absl::OkStatus();
  }
  return in.Error(absl::StrCat("unknown keyword \"", keyword.substr(0, 40), "\""));
}

}  // namespace

absl::StatusOr<MeshFile> ParseVtkLegacy(absl::string_view text, absl::string_view path) {
  TextScanner in(text, path);
  Parsed p;
  absl::string_view header = in.RestOfLine();
  if (!absl::ConsumePrefix(&header, "# vtk DataFile Version ")) {
    return in.Error("not a legacy VTK file: first line is not \"# vtk DataFile Version x.y\"");
  }
  if (header.empty() || !absl::ascii_isdigit(header[0])) {
    return in.Error("bad legacy VTK version");
  }
  p.major_version = header[0] - '0';
  in.RestOfLine();  // title
  const std::string format = absl::AsciiStrToUpper(absl::StripAsciiWhitespace(in.RestOfLine()));
  if (format == "BINARY") return in.Error("binary legacy VTK is not supported; write it as ASCII");
  if (format != "ASCII") return in.Error("third line must be ASCII or BINARY");

  int64_t section_size = -1;  // tuples in the current POINT_DATA / CELL_DATA section
  bool point_section = false;
  while (!in.AtEnd()) {
    absl::StatusOr<absl::string_view> token = in.Token("a keyword");
    if (!token.ok()) return token.status();
    const std::string keyword = absl::AsciiStrToLower(*token);
    if (keyword == "dataset") {
      absl::StatusOr<absl::string_view> kind = in.Token("the dataset type");
      if (!kind.ok()) return kind.status();
      if (!absl::EqualsIgnoreCase(*kind, "UNSTRUCTURED_GRID")) {
        return in.Error(absl::StrCat("DATASET ", kind->substr(0, 40),
                                     ": only UNSTRUCTURED_GRID holds a tetrahedral mesh"));
      }
    } else if (keyword == "points") {
      absl::StatusOr<int64_t> n = in.IntIn("the POINTS count", 0, (int64_t{1} << 32) - 1);
      if (!n.ok()) return n.status();
      if (absl::Status s = in.Token("the POINTS type").status(); !s.ok()) return s;
      if (absl::Status s = ReadNumbers(in, 3 * *n, "point coordinates", p.points); !s.ok()) {
        return s;
      }
      p.have_points = true;
    } else if (keyword == "cells") {
      if (absl::Status s = ReadCells(in, p); !s.ok()) return s;
      p.have_cells = true;
    } else if (keyword == "cell_types") {
      absl::StatusOr<int64_t> n = in.IntIn("the CELL_TYPES count", 0, kMaxCount);
      if (!n.ok()) return n.status();
      if (absl::Status s = ReadInts(in, *n, "cell types", p.cells.types); !s.ok()) return s;
      p.have_types = true;
    } else if (keyword == "point_data" || keyword == "cell_data") {
      absl::StatusOr<int64_t> n = in.IntIn(absl::StrCat("the ", *token, " count"), 0, kMaxCount);
      if (!n.ok()) return n.status();
      section_size = *n;
      point_section = keyword == "point_data";
      const size_t expected = point_section ? p.points.size() / 3 : p.cells.types.size();
      if (static_cast<size_t>(*n) != expected) {
        return in.Error(absl::StrCat(*token, " ", *n, " does not match the ", expected,
                                     point_section ? " points" : " cells"));
      }
    } else if (section_size >= 0) {
      if (absl::Status s = ReadAttribute(in, p, keyword, section_size, point_section); !s.ok()) {
        return s;
      }
    } else {
      return in.Error(absl::StrCat("unexpected keyword \"", token->substr(0, 40), "\""));
    }
  }
  if (!p.have_points || !p.have_cells || !p.have_types) {
    return in.Error("truncated: POINTS, CELLS and CELL_TYPES are all required");
  }
  if (p.major_version < 5 && p.cells.offsets.size() != p.cells.types.size() + 1) {
    return in.Error(absl::StrCat("CELL_TYPES has ", p.cells.types.size(), " entries for ",
                                 p.cells.offsets.size() - 1, " cells"));
  }
  MeshFile file;
  const size_t v = p.points.size() / 3;
  file.mesh.points.resize(v);
  for (size_t i = 0; i < v; ++i) {
    file.mesh.points[i] = {p.points[3 * i], p.points[3 * i + 1], p.points[3 * i + 2]};
  }
  file.mesh.values = std::move(p.values);
  if (absl::Status s = CellsToTets(p.cells, p.cell_data, v, path, file); !s.ok()) {
    return s;
  }
  if (absl::Status s = ValidateMeshFile(file, path); !s.ok()) return s;
  return file;
}

std::string FormatVtkLegacy(const MeshFile& file) {
  const Mesh& mesh = file.mesh;
  const size_t v = mesh.points.size();
  const size_t t = mesh.tets.size();
  std::string out = "# vtk DataFile Version 3.0\ntetrefine mesh\nASCII\n";
  absl::StrAppend(&out, "DATASET UNSTRUCTURED_GRID\nPOINTS ", v, " double\n");
  for (const Vec3& p : mesh.points) {
    AppendDouble(out, p[0]);
    out += ' ';
    AppendDouble(out, p[1]);
    out += ' ';
    AppendDouble(out, p[2]);
    out += '\n';
  }
  absl::StrAppend(&out, "CELLS ", t, " ", 5 * t, "\n");
  for (const Tet& tet : mesh.tets) {
    absl::StrAppend(&out, "4 ", tet[0], " ", tet[1], " ", tet[2], " ", tet[3], "\n");
  }
  absl::StrAppend(&out, "CELL_TYPES ", t, "\n");
  for (size_t i = 0; i < t; ++i) out += "10\n";
  if (!mesh.values.empty()) {
    absl::StrAppend(&out, "POINT_DATA ", v, "\nSCALARS value double 1\nLOOKUP_TABLE default\n");
    for (double value : mesh.values) {
      AppendDouble(out, value);
      out += '\n';
    }
  }
  if (!file.tet_iteration.empty() || !file.tet_quality.empty()) {
    absl::StrAppend(&out, "CELL_DATA ", t, "\n");
    if (!file.tet_iteration.empty()) {
      out += "SCALARS iteration int 1\nLOOKUP_TABLE default\n";
      for (int32_t it : file.tet_iteration) absl::StrAppend(&out, it, "\n");
    }
    if (!file.tet_quality.empty()) {
      out += "SCALARS quality float 1\nLOOKUP_TABLE default\n";
      for (float q : file.tet_quality) {
        AppendFloat(out, q);
        out += '\n';
      }
    }
  }
  return out;
}

}  // namespace tetrefine::io
