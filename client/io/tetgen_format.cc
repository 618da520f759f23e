// TetGen .node/.ele. See tetgen_format.h.
#include "client/io/tetgen_format.h"

#include <cmath>
#include <cstdint>
#include <vector>

#include "absl/strings/ascii.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "client/io/number_text.h"
#include "client/io/text_scanner.h"
#include "core/huge_pages.h"

namespace tetrefine::io {
namespace {

constexpr int64_t kMaxCount = int64_t{1} << 40;

// The first index of a file's list: 0 or 1, which every later index follows.
absl::StatusOr<int64_t> IndexBase(TextScanner& in, absl::string_view what) {
  absl::StatusOr<int64_t> first = in.Int(what);
  if (!first.ok()) return first.status();
  if (*first != 0 && *first != 1) {
    return in.Error(
        absl::StrCat("the first ", what, " is ", *first, ": TetGen numbers from 0 or 1"));
  }
  return first;
}

absl::Status ExpectIndex(TextScanner& in, int64_t want, absl::string_view what) {
  absl::StatusOr<int64_t> index = in.Int(what);
  if (!index.ok()) return index.status();
  if (*index != want) {
    return in.Error(absl::StrCat(what, " ", *index, " out of order: expected ", want,
                                 " (indices run consecutively)"));
  }
  return absl::OkStatus();
}

}  // namespace

std::string TetgenNodePath(const std::string& ele_path) {
  // ".ELE" pairs with ".NODE": files copied from a case-insensitive file system (or written by
  // tools that upper-case names) keep both in capitals. Reading only ".node" refused such a
  // pair (found by a file-format sweep); writing X.ELE made X.node.
  const bool upper = ele_path.size() >= 4 && absl::ascii_isupper(ele_path[ele_path.size() - 3]);
  return ele_path.substr(0, ele_path.size() - 4) + (upper ? ".NODE" : ".node");
}

absl::StatusOr<MeshFile> ParseTetgen(absl::string_view node_text, absl::string_view ele_text,
                                     absl::string_view node_path, absl::string_view ele_path) {
  MeshFile file;
  // Points.
  TextScanner nodes(node_text, node_path, '#');
  absl::StatusOr<int64_t> n = nodes.IntIn("the point count", 0, (int64_t{1} << 32) - 1);
  if (!n.ok()) return n.status();
  absl::StatusOr<int64_t> dim = nodes.Int("the dimension");
  if (!dim.ok()) return dim.status();
  if (*dim != 3) return nodes.Error(absl::StrCat("dimension ", *dim, ": only 3D meshes are read"));
  absl::StatusOr<int64_t> attributes = nodes.IntIn("the point attribute count", 0, 1 << 20);
  if (!attributes.ok()) return attributes.status();
  absl::StatusOr<int64_t> markers = nodes.IntIn("the boundary marker flag", 0, 1);
  if (!markers.ok()) return markers.status();
  // A point line holds at least 4 numbers of 2 characters.
  if (absl::Status s = nodes.CheckCount(*n, 8 + 2 * (*attributes + *markers), "points"); !s.ok()) {
    return s;
  }
  ReserveHuge(file.mesh.points, *n);
  int64_t node_base = 0;
  for (int64_t i = 0; i < *n; ++i) {
    if (i == 0) {
      absl::StatusOr<int64_t> base = IndexBase(nodes, "point index");
      if (!base.ok()) return base.status();
      node_base = *base;
    } else if (absl::Status s = ExpectIndex(nodes, node_base + i, "point index"); !s.ok()) {
      return s;
    }
    Vec3 p;
    for (int a = 0; a < 3; ++a) {
      absl::StatusOr<double> x = nodes.FiniteDouble("a coordinate");
      if (!x.ok()) return x.status();
      p[a] = *x;
    }
    file.mesh.points.push_back(p);
    for (int64_t k = 0; k < *attributes; ++k) {
      if (absl::Status s = nodes.Double("a point attribute").status(); !s.ok()) return s;
    }
    if (*markers == 1) {
      // meshio writes markers as floats ("0.0"); they are dropped, so any number will do.
      if (absl::Status s = nodes.Double("a boundary marker").status(); !s.ok()) return s;
    }
  }
  if (!nodes.AtEnd()) return nodes.Error("more points than the header's count");
  for (int64_t k = 0; k < *attributes; ++k) {
    file.dropped_arrays.push_back(DroppedArray(true, absl::StrCat("tetgen attribute ", k + 1)));
  }
  if (*markers == 1) file.dropped_arrays.push_back(DroppedArray(true, "tetgen boundary marker"));

  // Tets.
  TextScanner eles(ele_text, ele_path, '#');
  absl::StatusOr<int64_t> m = eles.IntIn("the tet count", 0, kMaxCount);
  if (!m.ok()) return m.status();
  absl::StatusOr<int64_t> corners = eles.Int("the nodes per tet");
  if (!corners.ok()) return corners.status();
  if (*corners == 10) {
    return eles.Error(
        "10 nodes per tet: quadratic tetrahedra (tetra10, tetgen -o2) are not read; only linear "
        "tets");
  }
  if (*corners != 4) return eles.Error(absl::StrCat(*corners, " nodes per tet: expected 4"));
  absl::StatusOr<int64_t> regions = eles.IntIn("the region attribute count", 0, 1 << 20);
  if (!regions.ok()) return regions.status();
  if (absl::Status s = eles.CheckCount(*m, 10 + 2 * *regions, "tets"); !s.ok()) return s;
  ReserveHuge(file.mesh.tets, *m);
  if (*regions > 0) {
    file.label_name = "tetgen:ref";
    ReserveHuge(file.mesh.labels, *m);
  }
  int64_t ele_base = 0;
  for (int64_t t = 0; t < *m; ++t) {
    if (t == 0) {
      absl::StatusOr<int64_t> base = IndexBase(eles, "tet index");
      if (!base.ok()) return base.status();
      ele_base = *base;
    } else if (absl::Status s = ExpectIndex(eles, ele_base + t, "tet index"); !s.ok()) {
      return s;
    }
    Tet tet;
    for (int c = 0; c < 4; ++c) {
      absl::StatusOr<int64_t> v = eles.IntIn("a tet corner", node_base, node_base + *n - 1);
      if (!v.ok()) return v.status();
      tet[c] = static_cast<uint32_t>(*v - node_base);
    }
    file.mesh.tets.push_back(tet);
    for (int64_t k = 0; k < *regions; ++k) {
      absl::StatusOr<double> attribute = eles.Double("a region attribute");
      if (!attribute.ok()) return attribute.status();
      if (k > 0) continue;
      // int32's whole range: the writer puts INT32_MIN there as any other label (a CLI sweep
      // found -2147483648 written and then refused).
      if (!(*attribute >= -2147483648.0 && *attribute <= 2147483647.0) ||
          *attribute != std::floor(*attribute)) {
        return eles.Error(absl::StrCat("region attribute ", absl::StrFormat("%.17g", *attribute),
                                       " of tet ", ele_base + t,
                                       " is not a whole number in int32's range (a label)"));
      }
      file.mesh.labels.push_back(static_cast<int32_t>(*attribute));
    }
  }
  if (!eles.AtEnd()) return eles.Error("more tets than the header's count");
  for (int64_t k = 1; k < *regions; ++k) {
    file.dropped_arrays.push_back(
        DroppedArray(false, absl::StrCat("tetgen region attribute ", k + 1)));
  }
  return file;
}

TetgenFiles FormatTetgen(const MeshFile& file) {
  const Mesh& mesh = file.mesh;
  const bool labels = !mesh.labels.empty();
  TetgenFiles out;
  // Shortest round-trip numbers (std::to_chars), as the other text writers: the coordinates come
  // back to the bit, and it is several times faster than printf's %.17g on refined meshes.
  out.node = absl::StrCat(mesh.points.size(), " 3 0 0\n");
  for (size_t i = 0; i < mesh.points.size(); ++i) {
    absl::StrAppend(&out.node, i + 1);
    for (int a = 0; a < 3; ++a) {
      out.node += ' ';
      AppendDouble(out.node, mesh.points[i][a]);
    }
    out.node += '\n';
  }
  out.node += "# Generated by tetrefine\n";
  out.ele = absl::StrCat(mesh.tets.size(), " 4 ", labels ? 1 : 0, "\n");
  for (size_t t = 0; t < mesh.tets.size(); ++t) {
    const Tet& k = mesh.tets[t];
    absl::StrAppend(&out.ele, t + 1, " ", k[0] + 1, " ", k[1] + 1, " ", k[2] + 1, " ", k[3] + 1);
    if (labels) absl::StrAppend(&out.ele, " ", mesh.labels[t]);
    out.ele += '\n';
  }
  out.ele += "# Generated by tetrefine\n";
  return out;
}

}  // namespace tetrefine::io
