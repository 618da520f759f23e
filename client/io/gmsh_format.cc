#include "client/io/gmsh_format.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <unordered_map>
#include <utility>
#include <vector>

#include "absl/strings/ascii.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/strip.h"
#include "client/io/number_text.h"
#include "client/io/text_scanner.h"

namespace tetrefine::io {
namespace {

constexpr int kGmshTet = 4;
constexpr int64_t kMaxCount = int64_t{1} << 40;

// Nodes per element of Gmsh element types 1..31; 0 for unknown.
int NodesPerElement(int64_t type) {
  static constexpr int kNodes[] = {0, 2,  3,  4,  4, 8,  6,  5,  3,  6,  9, 10, 27, 18, 14, 1,
                                   8, 20, 15, 13, 9, 10, 12, 15, 15, 21, 4, 5,  6,  20, 35, 56};
  return type >= 1 && type <= 31 ? kNodes[type] : 0;
}

// Maps tags (node or element numbers, arbitrary positive integers) to dense indices.
class TagMap {
 public:
  void Add(int64_t tag, uint32_t index) { map_[tag] = index; }
  bool Find(int64_t tag, uint32_t& index) const {
    const auto it = map_.find(tag);
    if (it == map_.end()) return false;
    index = it->second;
    return true;
  }
  size_t size() const { return map_.size(); }

 private:
  std::unordered_map<int64_t, uint32_t> map_;
};

class GmshParser {
 public:
  GmshParser(absl::string_view text, absl::string_view path) : in_(text, path), path_(path) {}

  absl::StatusOr<MeshFile> Parse(GmshReadInfo* info) {
    if (absl::Status s = MeshFormat(); !s.ok()) return s;
    while (!in_.AtEnd()) {
      absl::StatusOr<absl::string_view> token = in_.Token("a section");
      if (!token.ok()) return token.status();
      absl::string_view section = *token;
      if (!absl::ConsumePrefix(&section, "$")) {
        return in_.Error(absl::StrCat("expected a $Section, got \"", token->substr(0, 40), "\""));
      }
      absl::Status s;
      if (section == "Nodes") {
        s = version_ >= 4 ? Nodes41() : Nodes22();
      } else if (section == "Elements") {
        s = version_ >= 4 ? Elements41() : Elements22();
      } else if (section == "NodeData" || section == "ElementData") {
        s = Data(section == "NodeData");
      } else {
        s = SkipSection(section);
        if (s.ok()) continue;
      }
      if (!s.ok()) return s;
      if (absl::Status end = ExpectEnd(section); !end.ok()) return end;
    }
    if (!have_nodes_ || !have_elements_) {
      return in_.Error("truncated or incomplete: $Nodes and $Elements are both required");
    }
    if (have_values_) {
      const size_t missing = std::count_if(file_.mesh.values.begin(), file_.mesh.values.end(),
                                           [](double x) { return std::isnan(x); });
      if (missing > 0) {
        return in_.Error(absl::StrCat("$NodeData \"value\" misses ", missing, " of ",
                                      file_.mesh.values.size(), " nodes"));
      }
    }
    for (const auto& [name, array] :
         {std::pair{"iteration", &iteration_}, std::pair{"quality", &quality_}}) {
      const size_t missing =
          std::count_if(array->begin(), array->end(), [](double x) { return std::isnan(x); });
      if (missing > 0) {
        return in_.Error(absl::StrCat("$ElementData \"", name, "\" misses ", missing, " of ",
                                      array->size(), " tetrahedra"));
      }
    }
    for (double it : iteration_) {
      if (it != std::floor(it) || it < std::numeric_limits<int32_t>::min() ||
          it > std::numeric_limits<int32_t>::max()) {
        return in_.Error(absl::StrCat("iteration ", it, " is not a 32-bit integer"));
      }
      file_.tet_iteration.push_back(static_cast<int32_t>(it));
    }
    for (double q : quality_) file_.tet_quality.push_back(static_cast<float>(q));
    if (info != nullptr) info->ignored_elements = ignored_elements_;
    if (absl::Status s = ValidateMeshFile(file_, path_); !s.ok()) return s;
    return std::move(file_);
  }

 private:
  absl::Status MeshFormat() {
    absl::StatusOr<absl::string_view> first = in_.Token("$MeshFormat");
    if (!first.ok()) return first.status();
    if (*first != "$MeshFormat") return in_.Error("not a Gmsh file: no $MeshFormat");
    absl::StatusOr<double> version = in_.Double("the format version");
    if (!version.ok()) return version.status();
    absl::StatusOr<int64_t> file_type = in_.Int("the file type");
    if (!file_type.ok()) return file_type.status();
    if (absl::Status s = in_.Int("the data size").status(); !s.ok()) return s;
    if (*file_type != 0) return in_.Error("binary .msh is not supported; save it as ASCII");
    if (*version >= 2.0 && *version < 3.0) {
      version_ = 2;
    } else if (*version == 4.1) {
      version_ = 4;
    } else {
      return in_.Error(
          absl::StrCat("MSH format ", *version, " is not supported (2.2 and 4.1 are)"));
    }
    return ExpectEnd("MeshFormat");
  }

  absl::Status ExpectEnd(absl::string_view section) {
    const std::string end = absl::StrCat("$End", section);
    absl::StatusOr<absl::string_view> token = in_.Token(end);
    if (!token.ok()) return token.status();
    if (*token != end) {
      return in_.Error(
          absl::StrCat("expected ", end, ", got \"", token->substr(0, 40), "\" (wrong count?)"));
    }
    return absl::OkStatus();
  }

  absl::Status SkipSection(absl::string_view section) {
    const std::string end = absl::StrCat("$End", section);
    while (true) {
      absl::StatusOr<absl::string_view> token = in_.Token(end);
      if (!token.ok()) return token.status();
      if (*token == end) return absl::OkStatus();
    }
  }

  absl::Status StartNodes(int64_t count) {
    if (have_nodes_) return in_.Error("second $Nodes section");
    if (count > (int64_t{1} << 32) - 1) return in_.Error("too many nodes");
    // A node is at least "t x y z" with separators: 8 bytes.
    if (absl::Status s = in_.CheckCount(count, 8, "nodes"); !s.ok()) return s;
    file_.mesh.points.resize(count);
    have_nodes_ = true;
    return absl::OkStatus();
  }

  absl::Status Point(uint32_t index) {
    for (double& x : file_.mesh.points[index]) {
      absl::StatusOr<double> value = in_.FiniteDouble("a node coordinate");
      if (!value.ok()) return value.status();
      x = *value;
    }
    return absl::OkStatus();
  }

  absl::Status AddNodeTag(int64_t tag, uint32_t index) {
    uint32_t existing;
    if (node_tags_.Find(tag, existing))
      return in_.Error(absl::StrCat("node tag ", tag, " repeats"));
    node_tags_.Add(tag, index);
    return absl::OkStatus();
  }

  absl::Status Nodes22() {
    absl::StatusOr<int64_t> count = in_.IntIn("the node count", 0, kMaxCount);
    if (!count.ok()) return count.status();
    if (absl::Status s = StartNodes(*count); !s.ok()) return s;
    for (int64_t i = 0; i < *count; ++i) {
      absl::StatusOr<int64_t> tag = in_.IntIn("a node tag", 1, kMaxCount);
      if (!tag.ok()) return tag.status();
      if (absl::Status s = AddNodeTag(*tag, static_cast<uint32_t>(i)); !s.ok()) return s;
      if (absl::Status s = Point(static_cast<uint32_t>(i)); !s.ok()) return s;
    }
    return absl::OkStatus();
  }

  absl::Status Nodes41() {
    absl::StatusOr<int64_t> blocks = in_.IntIn("the node block count", 0, kMaxCount);
    if (!blocks.ok()) return blocks.status();
    absl::StatusOr<int64_t> count = in_.IntIn("the node count", 0, kMaxCount);
    if (!count.ok()) return count.status();
    for (const char* what : {"the minimum node tag", "the maximum node tag"}) {
      if (absl::Status s = in_.Int(what).status(); !s.ok()) return s;
    }
    if (absl::Status s = StartNodes(*count); !s.ok()) return s;
    int64_t next = 0;
    for (int64_t b = 0; b < *blocks; ++b) {
      absl::StatusOr<int64_t> dim = in_.IntIn("an entity dimension", 0, 3);
      if (!dim.ok()) return dim.status();
      if (absl::Status s = in_.Int("an entity tag").status(); !s.ok()) return s;
      absl::StatusOr<int64_t> parametric = in_.IntIn("the parametric flag", 0, 1);
      if (!parametric.ok()) return parametric.status();
      absl::StatusOr<int64_t> in_block = in_.IntIn("a block's node count", 0, *count - next);
      if (!in_block.ok()) return in_block.status();
      for (int64_t i = 0; i < *in_block; ++i) {
        absl::StatusOr<int64_t> tag = in_.IntIn("a node tag", 1, kMaxCount);
        if (!tag.ok()) return tag.status();
        if (absl::Status s = AddNodeTag(*tag, static_cast<uint32_t>(next + i)); !s.ok()) {
          return s;
        }
      }
      for (int64_t i = 0; i < *in_block; ++i) {
        if (absl::Status s = Point(static_cast<uint32_t>(next + i)); !s.ok()) return s;
        // Parametric nodes carry `dim` extra coordinates (u, v, w) this mesh does not need.
        for (int64_t p = 0; p < (*parametric ? *dim : 0); ++p) {
          if (absl::Status s = in_.Double("a parametric coordinate").status(); !s.ok()) return s;
        }
      }
      next += *in_block;
    }
    if (next != *count) {
      return in_.Error(absl::StrCat("node blocks hold ", next, " nodes, header says ", *count));
    }
    return absl::OkStatus();
  }

  // Reads the node tags of one element of `type`, storing it when it is a tet.
  absl::Status Element(int64_t tag, int64_t type) {
    const int nodes = NodesPerElement(type);
    if (nodes == 0) return in_.Error(absl::StrCat("unknown element type ", type));
    Tet tet{};
    for (int k = 0; k < nodes; ++k) {
      absl::StatusOr<int64_t> node = in_.Int("an element node tag");
      if (!node.ok()) return node.status();
      if (type != kGmshTet) continue;
      if (!node_tags_.Find(*node, tet[k])) {
        return in_.Error(
            absl::StrCat("element ", tag, " uses node ", *node, ", which is not defined"));
      }
    }
    if (type != kGmshTet) {
      ++ignored_elements_;
      return absl::OkStatus();
    }
    uint32_t existing;
    if (tet_tags_.Find(tag, existing))
      return in_.Error(absl::StrCat("element tag ", tag, " repeats"));
    tet_tags_.Add(tag, static_cast<uint32_t>(file_.mesh.tets.size()));
    file_.mesh.tets.push_back(tet);
    return absl::OkStatus();
  }

  absl::Status StartElements(int64_t count) {
    if (!have_nodes_) return in_.Error("$Elements before $Nodes");
    if (have_elements_) return in_.Error("second $Elements section");
    // An element is at least "t n" with separators: 4 bytes.
    if (absl::Status s = in_.CheckCount(count, 4, "elements"); !s.ok()) return s;
    have_elements_ = true;
    return absl::OkStatus();
  }

  absl::Status Elements22() {
    absl::StatusOr<int64_t> count = in_.IntIn("the element count", 0, kMaxCount);
    if (!count.ok()) return count.status();
    if (absl::Status s = StartElements(*count); !s.ok()) return s;
    for (int64_t i = 0; i < *count; ++i) {
      absl::StatusOr<int64_t> tag = in_.Int("an element tag");
      if (!tag.ok()) return tag.status();
      absl::StatusOr<int64_t> type = in_.Int("an element type");
      if (!type.ok()) return type.status();
      absl::StatusOr<int64_t> tags = in_.IntIn("an element's tag count", 0, 1 << 16);
      if (!tags.ok()) return tags.status();
      for (int64_t k = 0; k < *tags; ++k) {
        if (absl::Status s = in_.Int("an element tag").status(); !s.ok()) return s;
      }
      if (absl::Status s = Element(*tag, *type); !s.ok()) return s;
    }
    return absl::OkStatus();
  }

  absl::Status Elements41() {
    absl::StatusOr<int64_t> blocks = in_.IntIn("the element block count", 0, kMaxCount);
    if (!blocks.ok()) return blocks.status();
    absl::StatusOr<int64_t> count = in_.IntIn("the element count", 0, kMaxCount);
    if (!count.ok()) return count.status();
    for (const char* what : {"the minimum element tag", "the maximum element tag"}) {
      if (absl::Status s = in_.Int(what).status(); !s.ok()) return s;
    }
    if (absl::Status s = StartElements(*count); !s.ok()) return s;
    int64_t seen = 0;
    for (int64_t b = 0; b < *blocks; ++b) {
      for (const char* what : {"an entity dimension", "an entity tag"}) {
        if (absl::Status s = in_.Int(what).status(); !s.ok()) return s;
      }
      absl::StatusOr<int64_t> type = in_.Int("an element type");
      if (!type.ok()) return type.status();
      absl::StatusOr<int64_t> in_block = in_.IntIn("a block's element count", 0, *count - seen);
      if (!in_block.ok()) return in_block.status();
      for (int64_t i = 0; i < *in_block; ++i) {
        absl::StatusOr<int64_t> tag = in_.Int("an element tag");
        if (!tag.ok()) return tag.status();
        if (absl::Status s = Element(*tag, *type); !s.ok()) return s;
      }
      seen += *in_block;
    }
    if (seen != *count) {
      return in_.Error(
          absl::StrCat("element blocks hold ", seen, " elements, header says ", *count));
    }
    return absl::OkStatus();
  }

  // $NodeData / $ElementData: string tags (one per line, quoted), real tags, integer tags
  // (time step, components, entity count, ...), then "tag value..." per entity.
  absl::Status Data(bool node_data) {
    const char* section = node_data ? "$NodeData" : "$ElementData";
    if (!(node_data ? have_nodes_ : have_elements_)) {
      return in_.Error(absl::StrCat(section, node_data ? " before $Nodes" : " before $Elements"));
    }
    absl::StatusOr<int64_t> strings = in_.IntIn("the string tag count", 0, 1 << 10);
    if (!strings.ok()) return strings.status();
    in_.RestOfLine();
    std::string name;
    for (int64_t i = 0; i < *strings; ++i) {
      absl::string_view line = absl::StripAsciiWhitespace(in_.RestOfLine());
      absl::ConsumePrefix(&line, "\"");
      absl::ConsumeSuffix(&line, "\"");
      if (i == 0) name = std::string(line);
    }
    absl::StatusOr<int64_t> reals = in_.IntIn("the real tag count", 0, 1 << 10);
    if (!reals.ok()) return reals.status();
    for (int64_t i = 0; i < *reals; ++i) {
      if (absl::Status s = in_.Double("a real tag").status(); !s.ok()) return s;
    }
    absl::StatusOr<int64_t> ints = in_.IntIn("the integer tag count", 0, 1 << 10);
    if (!ints.ok()) return ints.status();
    if (*ints < 3) return in_.Error(absl::StrCat(section, " needs at least 3 integer tags"));
    int64_t components = 0;
    int64_t entities = 0;
    for (int64_t i = 0; i < *ints; ++i) {
      absl::StatusOr<int64_t> value = in_.Int("an integer tag");
      if (!value.ok()) return value.status();
      if (i == 1) components = *value;
      if (i == 2) entities = *value;
    }
    if (components < 1 || components > 9) {
      return in_.Error(absl::StrCat(section, " has ", components, " components"));
    }
    if (absl::Status s = in_.CheckCount(entities, 2 * (1 + components), "data entries"); !s.ok()) {
      return s;
    }
    std::vector<double>* target = nullptr;
    if (components == 1) {
      if (node_data && name == "value") {
        file_.mesh.values.assign(file_.mesh.points.size(), std::nan(""));
        have_values_ = true;
        target = &file_.mesh.values;
      } else if (!node_data && (name == "iteration" || name == "quality")) {
        target = name == "iteration" ? &iteration_ : &quality_;
        target->assign(file_.mesh.tets.size(), std::nan(""));
      }
    }
    for (int64_t i = 0; i < entities; ++i) {
      absl::StatusOr<int64_t> tag = in_.Int("a data entity tag");
      if (!tag.ok()) return tag.status();
      for (int64_t c = 0; c < components; ++c) {
        absl::StatusOr<double> value = in_.Double("a data value");
        if (!value.ok()) return value.status();
        if (target == nullptr) continue;
        uint32_t index;
        if (node_data) {
          if (!node_tags_.Find(*tag, index)) {
            return in_.Error(absl::StrCat("$NodeData names node ", *tag, ", which is not defined"));
          }
        } else if (!tet_tags_.Find(*tag, index)) {
          continue;  // data of an ignored (non-tet) element
        }
        if (std::isnan(*value)) return in_.Error(absl::StrCat("value of entity ", *tag, " is NaN"));
        (*target)[index] = *value;
      }
    }
    return absl::OkStatus();
  }

  TextScanner in_;
  absl::string_view path_;
  int version_ = 0;
  bool have_nodes_ = false;
  bool have_elements_ = false;
  bool have_values_ = false;
  MeshFile file_;
  TagMap node_tags_;
  TagMap tet_tags_;
  std::vector<double> iteration_;
  std::vector<double> quality_;
  int64_t ignored_elements_ = 0;
};

void AppendDataHeader(std::string& out, const char* section, const char* name, size_t count) {
  absl::StrAppend(&out, "$", section, "\n1\n\"", name, "\"\n1\n0\n3\n0\n1\n", count, "\n");
}

}  // namespace

absl::StatusOr<MeshFile> ParseGmsh(absl::string_view text, absl::string_view path,
                                   GmshReadInfo* info) {
  return GmshParser(text, path).Parse(info);
}

std::string FormatGmsh41(const MeshFile& file) {
  const Mesh& mesh = file.mesh;
  const size_t v = mesh.points.size();
  const size_t t = mesh.tets.size();
  std::string out = "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n";
  // One volume entity (tag 1) holding everything, with its bounding box.
  Vec3 lo{0, 0, 0};
  Vec3 hi{0, 0, 0};
  for (size_t i = 0; i < v; ++i) {
    for (int a = 0; a < 3; ++a) {
      lo[a] = i == 0 ? mesh.points[i][a] : std::min(lo[a], mesh.points[i][a]);
      hi[a] = i == 0 ? mesh.points[i][a] : std::max(hi[a], mesh.points[i][a]);
    }
  }
  out += "$Entities\n0 0 0 1\n1";
  for (double x : {lo[0], lo[1], lo[2], hi[0], hi[1], hi[2]}) {
    out += ' ';
    AppendDouble(out, x);
  }
  out += " 0 0\n$EndEntities\n";
  absl::StrAppend(&out, "$Nodes\n", v == 0 ? 0 : 1, " ", v, " ", v == 0 ? 0 : 1, " ", v, "\n");
  if (v > 0) {
    absl::StrAppend(&out, "3 1 0 ", v, "\n");
    for (size_t i = 1; i <= v; ++i) absl::StrAppend(&out, i, "\n");
    for (const Vec3& p : mesh.points) {
      AppendDouble(out, p[0]);
      out += ' ';
      AppendDouble(out, p[1]);
      out += ' ';
      AppendDouble(out, p[2]);
      out += '\n';
    }
  }
  out += "$EndNodes\n";
  absl::StrAppend(&out, "$Elements\n", t == 0 ? 0 : 1, " ", t, " ", t == 0 ? 0 : 1, " ", t, "\n");
  if (t > 0) {
    absl::StrAppend(&out, "3 1 ", kGmshTet, " ", t, "\n");
    for (size_t i = 0; i < t; ++i) {
      const Tet& tet = mesh.tets[i];
      absl::StrAppend(&out, i + 1, " ", tet[0] + 1, " ", tet[1] + 1, " ", tet[2] + 1, " ",
                      tet[3] + 1, "\n");
    }
  }
  out += "$EndElements\n";
  if (!mesh.values.empty()) {
    AppendDataHeader(out, "NodeData", "value", v);
    for (size_t i = 0; i < v; ++i) {
      absl::StrAppend(&out, i + 1, " ");
      AppendDouble(out, mesh.values[i]);
      out += '\n';
    }
    out += "$EndNodeData\n";
  }
  if (!file.tet_iteration.empty()) {
    AppendDataHeader(out, "ElementData", "iteration", t);
    for (size_t i = 0; i < t; ++i) absl::StrAppend(&out, i + 1, " ", file.tet_iteration[i], "\n");
    out += "$EndElementData\n";
  }
  if (!file.tet_quality.empty()) {
    AppendDataHeader(out, "ElementData", "quality", t);
    for (size_t i = 0; i < t; ++i) {
      absl::StrAppend(&out, i + 1, " ");
      AppendFloat(out, file.tet_quality[i]);
      out += '\n';
    }
    out += "$EndElementData\n";
  }
  return out;
}

}  // namespace tetrefine::io
