// Reading Gmsh .msh 2.2 and 4.1, ASCII and binary. See gmsh_format.h for what is kept.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <map>
#include <numeric>
#include <optional>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "absl/container/flat_hash_map.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_join.h"
#include "absl/strings/strip.h"
#include "client/io/byte_order.h"
#include "client/io/cell_census.h"
#include "client/io/gmsh_format.h"
#include "client/io/number_text.h"
#include "client/io/text_scanner.h"
#include "core/huge_pages.h"

namespace tetrefine::io {
namespace {

constexpr int64_t kMaxCount = int64_t{1} << 40;

// `items` described one by one and joined with ", ", the first four only, then "and N more": a
// note names a few of thousands, not all of them.
template <typename Items, typename Describe>
std::string FirstFewJoined(const Items& items, Describe describe) {
  constexpr size_t kListed = 4;
  std::vector<std::string> listed;
  for (const auto& item : items) {
    if (listed.size() == kListed) {
      listed.push_back(absl::StrCat("and ", items.size() - kListed, " more"));
      break;
    }
    listed.push_back(describe(item));
  }
  return absl::StrJoin(listed, ", ");
}

// Nodes per element of the Gmsh element types this reader knows; 0 for unknown.
int NodesPerElement(int64_t type) {
  static constexpr int kNodes[] = {0, 2,  3,  4,  4, 8,  6,  5,  3,  6,  9, 10, 27, 18, 14, 1,
                                   8, 20, 15, 13, 9, 10, 12, 15, 15, 21, 4, 5,  6,  20, 35, 56};
  if (type >= 1 && type <= 31) return kNodes[type];
  if (type == 92) return 64;   // 64-node third-order hexahedron
  if (type == 93) return 125;  // 125-node fourth-order hexahedron
  return 0;
}

CellKind GmshCellKind(int64_t type) {
  const auto skip = [](const char* singular, const char* plural) {
    return CellKind{singular, plural, CellFate::kSkip};
  };
  const auto volume = [](const char* singular, const char* plural) {
    return CellKind{singular, plural, CellFate::kUnsupported};
  };
  switch (type) {
    case 15:
      return skip("point", "points");
    case 1:
    case 8:
    case 26:
    case 27:
    case 28:
      return skip("line", "lines");
    case 2:
    case 9:
    case 20:
    case 21:
    case 22:
    case 23:
    case 24:
    case 25:
      return skip("triangle", "triangles");
    case 3:
    case 10:
    case 16:
      return skip("quadrangle", "quadrangles");
    case 5:
      return volume("hexahedron", "hexahedra");
    case 6:
      return volume("prism", "prisms");
    case 7:
      return volume("pyramid", "pyramids");
    case 11:
      return volume("second-order tetrahedron (tet10)", "second-order tetrahedra (tet10)");
    case 29:
    case 30:
    case 31:
      return volume("higher-order tetrahedron", "higher-order tetrahedra");
    case 12:
    case 17:
    case 92:
    case 93:
      return volume("higher-order hexahedron", "higher-order hexahedra");
    case 13:
    case 18:
      return volume("second-order prism", "second-order prisms");
    case 14:
    case 19:
      return volume("second-order pyramid", "second-order pyramids");
    default:
      break;
  }
  return CellKind{absl::StrCat("element of Gmsh type ", type),
                  absl::StrCat("elements of Gmsh type ", type), CellFate::kUnsupported};
}

// Maps tags (node or element numbers, arbitrary positive integers) to dense indices: a vector
// when the tags are nearly contiguous (what Gmsh writes), a hash map otherwise.
class TagMap {
 public:
  static constexpr uint32_t kNone = std::numeric_limits<uint32_t>::max();

  // Builds from tags[i] -> i. Returns the first repeated tag, or 0 when all are distinct.
  int64_t Build(const std::vector<int64_t>& tags) {
    dense_.clear();
    sparse_.clear();
    if (tags.empty()) return 0;
    const auto [lo, hi] = std::minmax_element(tags.begin(), tags.end());
    if (*lo >= 0 && *hi <= 4 * static_cast<int64_t>(tags.size()) + 1024) {
      dense_.assign(*hi + 1, kNone);
      for (size_t i = 0; i < tags.size(); ++i) {
        uint32_t& slot = dense_[tags[i]];
        if (slot != kNone) return tags[i];
        slot = static_cast<uint32_t>(i);
      }
      return 0;
    }
    sparse_.reserve(tags.size());
    for (size_t i = 0; i < tags.size(); ++i) {
      if (!sparse_.emplace(tags[i], static_cast<uint32_t>(i)).second) return tags[i];
    }
    return 0;
  }
  uint32_t Find(int64_t tag) const {
    if (!dense_.empty() || sparse_.empty()) {
      return tag >= 0 && static_cast<uint64_t>(tag) < dense_.size() ? dense_[tag] : kNone;
    }
    const auto it = sparse_.find(tag);
    return it == sparse_.end() ? kNone : it->second;
  }

 private:
  std::vector<uint32_t> dense_;
  absl::flat_hash_map<int64_t, uint32_t> sparse_;
};

class GmshParser {
 public:
  GmshParser(absl::string_view text, absl::string_view path) : in_(text, path), path_(path) {}

  absl::StatusOr<MeshFile> Parse(GmshReadInfo* info);

 private:
  // --- primitives: a token in ASCII files, fixed-size values in binary ones -----------------
  absl::StatusOr<absl::string_view> Binary(size_t count, size_t width, absl::string_view what) {
    if (count > static_cast<size_t>(kMaxCount) / width) {
      return in_.Error(absl::StrCat("impossible count of ", what));
    }
    return in_.Bytes(count * width, what);
  }
  template <typename T>
  T Load(absl::string_view bytes, size_t index) const {
    return LoadAs<T>(bytes, index * sizeof(T), order_);
  }
  // An int (4 bytes in binary files), range-checked.
  absl::StatusOr<int64_t> Int(absl::string_view what, int64_t lo, int64_t hi) {
    if (!binary_) return in_.IntIn(what, lo, hi);
    absl::StatusOr<absl::string_view> b = Binary(1, 4, what);
    if (!b.ok()) return b.status();
    const int64_t v = Load<int32_t>(*b, 0);
    if (v < lo || v > hi) {
      return in_.Error(absl::StrCat(what, " = ", v, " is out of range [", lo, ", ", hi, "]"));
    }
    return v;
  }
  // A size_t (8 bytes in binary 4.1 files), range-checked.
  absl::StatusOr<int64_t> Size(absl::string_view what, int64_t lo, int64_t hi) {
    if (!binary_) return in_.IntIn(what, lo, hi);
    absl::StatusOr<absl::string_view> b = Binary(1, 8, what);
    if (!b.ok()) return b.status();
    const uint64_t v = Load<uint64_t>(*b, 0);
    if (v < static_cast<uint64_t>(std::max<int64_t>(lo, 0)) || v > static_cast<uint64_t>(hi)) {
      return in_.Error(absl::StrCat(what, " = ", v, " is out of range [", lo, ", ", hi, "]"));
    }
    return static_cast<int64_t>(v);
  }
  absl::StatusOr<double> Real(absl::string_view what) {
    if (!binary_) return in_.Double(what);
    absl::StatusOr<absl::string_view> b = Binary(1, 8, what);
    if (!b.ok()) return b.status();
    return Load<double>(*b, 0);
  }
  // Ends the text line before a binary block (binary files only).
  void StartBinary() {
    if (binary_) in_.RestOfLine();
  }

  // --- sections ------------------------------------------------------------------------------
  absl::Status MeshFormat();
  absl::Status ExpectEnd(absl::string_view section);
  absl::Status SkipSection(absl::string_view section);
  absl::Status Entities();
  absl::Status PartitionedEntities();
  absl::Status PhysicalNames();
  absl::Status EntityLists(bool partitioned);
  absl::Status Nodes22();
  absl::Status Nodes41();
  absl::Status Elements22();
  // MSH 2 lists an element once per physical group of its elementary entity; keeps the first
  // copy of each tet (see the definition).
  void DropPhysicalCopies22();
  absl::Status Elements41();
  absl::Status Data(bool node_data);
  absl::Status StartNodes(int64_t count);
  absl::Status StartElements(int64_t count);
  absl::Status FinishNodes();
  // One element's nodes: stores it when it is a tet, counts it otherwise.
  absl::Status Element(int64_t tag, int64_t type, const int64_t* nodes, int64_t label);
  absl::Status CountOther(int64_t type, int64_t n);
  absl::StatusOr<MeshFile> Finish(GmshReadInfo* info);

  TextScanner in_;
  absl::string_view path_;
  int version_ = 0;
  bool binary_ = false;
  ByteOrder order_ = kNativeOrder;
  bool have_nodes_ = false;
  bool have_elements_ = false;
  bool any_physical_ = false;

  std::vector<Vec3> points_;
  std::vector<int64_t> node_tags_;
  TagMap node_index_;
  // Physical tags of 4.1 entities, keyed by dimension * 2^32 + entity tag.
  absl::flat_hash_map<int64_t, int64_t> entity_physical_;
  std::map<int32_t, std::string> region_names_;  // $PhysicalNames of dimension 3
  // Volume entities in more than one physical group: {entity, a group after its first}, in file
  // order. A tet keeps one label, its entity's first group; the others are named as dropped.
  std::vector<std::pair<int64_t, int64_t>> other_groups_;

  // Tets as read, in file order.
  std::vector<Tet> tets_;
  std::vector<int64_t> tet_tags_;
  std::vector<int32_t> labels_;
  std::vector<int64_t> entities22_;   // MSH 2: each tet's elementary entity (its second tag)
  std::set<int64_t> tet_entities41_;  // MSH 4: the volume entities whose blocks hold tets
  TagMap tet_index_;                  // built once the elements are read
  std::vector<double> values_;
  std::vector<double> iteration_;
  std::vector<double> quality_;
  absl::flat_hash_map<int64_t, int64_t> other_types_;  // skipped or refused element counts
};

absl::Status GmshParser::MeshFormat() {
  absl::StatusOr<absl::string_view> first = in_.Token("$MeshFormat");
  if (!first.ok()) return first.status();
  if (*first != "$MeshFormat") return in_.Error("not a Gmsh file: no $MeshFormat");
  absl::StatusOr<double> version = in_.Double("the format version");
  if (!version.ok()) return version.status();
  absl::StatusOr<int64_t> file_type = in_.IntIn("the file type", 0, 1);
  if (!file_type.ok()) return file_type.status();
  absl::StatusOr<int64_t> data_size = in_.Int("the data size");
  if (!data_size.ok()) return data_size.status();
  if (*version >= 2.0 && *version < 3.0) {
    version_ = 2;
  } else if (*version == 4.1) {
    version_ = 4;
  } else {
    return in_.Error(absl::StrCat("MSH format ", *version, " is not supported (2.2 and 4.1 are)"));
  }
  binary_ = *file_type == 1;
  if (binary_) {
    if (*data_size != 8) {
      return in_.Error(absl::StrCat("data size ", *data_size, " is not supported (8 is)"));
    }
    // The integer 1, written natively: it tells the file's byte order.
    in_.RestOfLine();
    absl::StatusOr<absl::string_view> one = in_.Bytes(4, "the endianness word");
    if (!one.ok()) return one.status();
    if (LoadAs<int32_t>(*one, 0, ByteOrder::kLittle) == 1) {
      order_ = ByteOrder::kLittle;
    } else if (LoadAs<int32_t>(*one, 0, ByteOrder::kBig) == 1) {
      order_ = ByteOrder::kBig;
    } else {
      return in_.Error("binary $MeshFormat: the endianness word is not 1");
    }
  }
  return ExpectEnd("MeshFormat");
}

absl::Status GmshParser::ExpectEnd(absl::string_view section) {
  const std::string end = absl::StrCat("$End", section);
  absl::StatusOr<absl::string_view> token = in_.Token(end);
  if (!token.ok()) return token.status();
  if (*token != end) {
    return in_.Error(
        absl::StrCat("expected ", end, ", got ", QuoteToken(*token), " (wrong count?)"));
  }
  return absl::OkStatus();
}

// Skips a section this reader does not use ($Periodic, $GhostElements, ...). Its end marker is
// searched as bytes: binary sections are not tokens.
absl::Status GmshParser::SkipSection(absl::string_view section) {
  const std::string end = absl::StrCat("$End", section);
  while (!in_.AtEndOfInput()) {
    absl::string_view line = absl::StripAsciiWhitespace(in_.RestOfLine());
    if (line == end) return absl::OkStatus();
  }
  return in_.Error(absl::StrCat("truncated: no ", end));
}

// $PhysicalNames (text in ASCII and binary files alike): "dim tag \"name\"" lines. The names
// of volume groups are the regions' names, written back to .msh outputs; they were dropped
// (found by a file-format sweep).
absl::Status GmshParser::PhysicalNames() {
  absl::StatusOr<int64_t> count = in_.IntIn("the physical name count", 0, kMaxCount);
  if (!count.ok()) return count.status();
  if (absl::Status s = in_.CheckCount(*count, 6, "physical names"); !s.ok()) return s;
  for (int64_t i = 0; i < *count; ++i) {
    absl::StatusOr<int64_t> dim = in_.IntIn("a physical group dimension", 0, 3);
    if (!dim.ok()) return dim.status();
    absl::StatusOr<int64_t> tag = in_.IntIn("a physical tag", std::numeric_limits<int32_t>::min(),
                                            std::numeric_limits<int32_t>::max());
    if (!tag.ok()) return tag.status();
    absl::string_view name = absl::StripAsciiWhitespace(in_.RestOfLine());
    if (name.size() < 2 || name.front() != '"' || name.back() != '"') {
      return in_.Error(absl::StrCat("physical name of ", *tag, ": expected a quoted name"));
    }
    name = name.substr(1, name.size() - 2);
    // A tag named twice keeps its first name, as Gmsh's own reader does: the last was kept, so
    // a round trip through tetrefine renamed the region (an outside review, 2026-11-29).
    if (*dim == 3 && !name.empty()) region_names_.emplace(static_cast<int32_t>(*tag), name);
  }
  return absl::OkStatus();
}

absl::Status GmshParser::Entities() { return EntityLists(/*partitioned=*/false); }

// $PartitionedEntities (a mesh saved with -part N): the element blocks then name the partitioned
// entities, whose physical tags are listed here. They were skipped, so every label of a
// partitioned 4.1 file was lost without a word (found by a file-format sweep).
absl::Status GmshParser::PartitionedEntities() {
  StartBinary();
  if (absl::Status s = Size("the partition count", 0, kMaxCount).status(); !s.ok()) return s;
  absl::StatusOr<int64_t> ghosts = Size("the ghost entity count", 0, kMaxCount);
  if (!ghosts.ok()) return ghosts.status();
  if (absl::Status s = in_.CheckCount(*ghosts, binary_ ? 8 : 4, "ghost entities"); !s.ok()) {
    return s;
  }
  for (int64_t g = 0; g < 2 * *ghosts; ++g) {
    if (absl::Status s = Int("a ghost entity tag or partition", std::numeric_limits<int32_t>::min(),
                             std::numeric_limits<int32_t>::max())
                             .status();
        !s.ok()) {
      return s;
    }
  }
  return EntityLists(/*partitioned=*/true);
}

// The four entity lists of $Entities, or of $PartitionedEntities, whose entities also name
// their parent entity and their partitions.
absl::Status GmshParser::EntityLists(bool partitioned) {
  int64_t counts[4];
  if (!partitioned) StartBinary();
  for (int64_t& c : counts) {
    absl::StatusOr<int64_t> n = Size("an entity count", 0, kMaxCount);
    if (!n.ok()) return n.status();
    c = *n;
  }
  constexpr int64_t kIntMin = std::numeric_limits<int32_t>::min();
  constexpr int64_t kIntMax = std::numeric_limits<int32_t>::max();
  for (int dim = 0; dim < 4; ++dim) {
    // An entity takes at least a tag, a box and two counts.
    if (absl::Status s = in_.CheckCount(counts[dim], 8, "entities"); !s.ok()) return s;
    for (int64_t e = 0; e < counts[dim]; ++e) {
      absl::StatusOr<int64_t> tag = Int("an entity tag", kIntMin, kIntMax);
      if (!tag.ok()) return tag.status();
      std::optional<int64_t> parent_key;
      if (partitioned) {
        absl::StatusOr<int64_t> parent_dim = Int("a parent entity dimension", 0, 3);
        if (!parent_dim.ok()) return parent_dim.status();
        absl::StatusOr<int64_t> parent_tag = Int("a parent entity tag", kIntMin, kIntMax);
        if (!parent_tag.ok()) return parent_tag.status();
        parent_key = (*parent_dim << 32) + *parent_tag;
        absl::StatusOr<int64_t> partitions = Size("a partition count", 0, kMaxCount);
        if (!partitions.ok()) return partitions.status();
        if (absl::Status s = in_.CheckCount(*partitions, binary_ ? 4 : 2, "partitions"); !s.ok()) {
          return s;
        }
        for (int64_t p = 0; p < *partitions; ++p) {
          if (absl::Status s = Int("a partition tag", kIntMin, kIntMax).status(); !s.ok()) {
            return s;
          }
        }
      }
      for (int k = 0; k < (dim == 0 ? 3 : 6); ++k) {
        if (absl::Status s = Real("an entity bounding box").status(); !s.ok()) return s;
      }
      absl::StatusOr<int64_t> physicals = Size("a physical tag count", 0, 1 << 20);
      if (!physicals.ok()) return physicals.status();
      const int64_t key = (int64_t{dim} << 32) + *tag;
      for (int64_t p = 0; p < *physicals; ++p) {
        absl::StatusOr<int64_t> physical = Int("a physical tag", kIntMin, kIntMax);
        if (!physical.ok()) return physical.status();
        // An entity may belong to several physical groups; the first is its label.
        if (p == 0) entity_physical_[key] = *physical;
        if (p > 0 && dim == 3) other_groups_.push_back({*tag, *physical});
      }
      // A partitioned entity without physical tags of its own takes its parent's.
      if (*physicals == 0 && parent_key.has_value()) {
        if (auto parent = entity_physical_.find(*parent_key); parent != entity_physical_.end()) {
          entity_physical_[key] = parent->second;
        }
      }
      if (dim > 0) {
        absl::StatusOr<int64_t> bounding = Size("a bounding entity count", 0, kMaxCount);
        if (!bounding.ok()) return bounding.status();
        if (absl::Status s = in_.CheckCount(*bounding, binary_ ? 4 : 2, "bounding entities");
            !s.ok()) {
          return s;
        }
        for (int64_t b = 0; b < *bounding; ++b) {
          if (absl::Status s = Int("a bounding entity", kIntMin, kIntMax).status(); !s.ok()) {
            return s;
          }
        }
      }
    }
  }
  return absl::OkStatus();
}

absl::Status GmshParser::StartNodes(int64_t count) {
  if (have_nodes_) return in_.Error("second $Nodes section");
  if (count > (int64_t{1} << 32) - 1) return in_.Error("too many nodes");
  // A node is at least "t x y z" with separators (8 bytes), or 4 + 24 bytes in binary.
  if (absl::Status s = in_.CheckCount(count, binary_ ? 28 : 8, "nodes"); !s.ok()) return s;
  ReserveHuge(points_, count);
  points_.resize(count);
  ReserveHuge(node_tags_, count);
  node_tags_.resize(count);
  have_nodes_ = true;
  return absl::OkStatus();
}

absl::Status GmshParser::FinishNodes() {
  for (const int64_t tag : node_tags_) {
    if (tag < 1) return in_.Error(absl::StrCat("node tag ", tag, " is not positive"));
  }
  // Vertices in node-tag order, as meshio and Gmsh's API return them: a writer that groups
  // nodes by entity (meshio does) keeps their order in the tags.
  if (!std::is_sorted(node_tags_.begin(), node_tags_.end())) {
    std::vector<uint32_t> order(node_tags_.size());
    std::iota(order.begin(), order.end(), 0u);
    std::sort(order.begin(), order.end(),
              [&](uint32_t a, uint32_t b) { return node_tags_[a] < node_tags_[b]; });
    std::vector<Vec3> points(points_.size());
    std::vector<int64_t> tags(node_tags_.size());
    for (size_t i = 0; i < order.size(); ++i) {
      points[i] = points_[order[i]];
      tags[i] = node_tags_[order[i]];
    }
    points_ = std::move(points);
    node_tags_ = std::move(tags);
  }
  if (const int64_t repeated = node_index_.Build(node_tags_); repeated != 0) {
    return in_.Error(absl::StrCat("node tag ", repeated, " repeats"));
  }
  for (size_t i = 0; i < points_.size(); ++i) {
    for (double x : points_[i]) {
      if (!std::isfinite(x)) {
        return in_.Error(absl::StrCat("node ", node_tags_[i],
                                      " has a coordinate that is not "
                                      "finite (",
                                      x, ")"));
      }
    }
  }
  return absl::OkStatus();
}

absl::Status GmshParser::Nodes22() {
  absl::StatusOr<int64_t> count = in_.IntIn("the node count", 0, kMaxCount);
  if (!count.ok()) return count.status();
  if (absl::Status s = StartNodes(*count); !s.ok()) return s;
  if (binary_) {
    StartBinary();
    absl::StatusOr<absl::string_view> bytes = Binary(*count, 28, "nodes");
    if (!bytes.ok()) return bytes.status();
    for (int64_t i = 0; i < *count; ++i) {
      const absl::string_view node = bytes->substr(28 * i, 28);
      node_tags_[i] = LoadAs<int32_t>(node, 0, order_);
      for (int a = 0; a < 3; ++a) points_[i][a] = LoadAs<double>(node, 4 + 8 * a, order_);
    }
  } else {
    for (int64_t i = 0; i < *count; ++i) {
      absl::StatusOr<int64_t> tag = in_.IntIn("a node tag", 1, kMaxCount);
      if (!tag.ok()) return tag.status();
      node_tags_[i] = *tag;
      for (double& x : points_[i]) {
        absl::StatusOr<double> value = in_.FiniteDouble("a node coordinate");
        if (!value.ok()) return value.status();
        x = *value;
      }
    }
  }
  return FinishNodes();
}

absl::Status GmshParser::Nodes41() {
  StartBinary();
  absl::StatusOr<int64_t> blocks = Size("the node block count", 0, kMaxCount);
  if (!blocks.ok()) return blocks.status();
  absl::StatusOr<int64_t> count = Size("the node count", 0, kMaxCount);
  if (!count.ok()) return count.status();
  for (const char* what : {"the minimum node tag", "the maximum node tag"}) {
    if (absl::Status s = Size(what, 0, std::numeric_limits<int64_t>::max()).status(); !s.ok()) {
      return s;
    }
  }
  if (absl::Status s = StartNodes(*count); !s.ok()) return s;
  int64_t next = 0;
  for (int64_t b = 0; b < *blocks; ++b) {
    absl::StatusOr<int64_t> dim = Int("an entity dimension", 0, 3);
    if (!dim.ok()) return dim.status();
    if (absl::Status s = Int("an entity tag", std::numeric_limits<int32_t>::min(),
                             std::numeric_limits<int32_t>::max())
                             .status();
        !s.ok()) {
      return s;
    }
    absl::StatusOr<int64_t> parametric = Int("the parametric flag", 0, 1);
    if (!parametric.ok()) return parametric.status();
    absl::StatusOr<int64_t> in_block = Size("a block's node count", 0, *count - next);
    if (!in_block.ok()) return in_block.status();
    const int64_t extra = *parametric ? *dim : 0;  // u, v, w this mesh does not need
    if (binary_) {
      absl::StatusOr<absl::string_view> tags = Binary(*in_block, 8, "node tags");
      if (!tags.ok()) return tags.status();
      for (int64_t i = 0; i < *in_block; ++i) {
        const uint64_t tag = Load<uint64_t>(*tags, i);
        node_tags_[next + i] =
            tag > static_cast<uint64_t>(kMaxCount) ? -1 : static_cast<int64_t>(tag);
      }
      absl::StatusOr<absl::string_view> xyz =
          Binary(*in_block * (3 + extra), 8, "node coordinates");
      if (!xyz.ok()) return xyz.status();
      for (int64_t i = 0; i < *in_block; ++i) {
        for (int a = 0; a < 3; ++a) points_[next + i][a] = Load<double>(*xyz, i * (3 + extra) + a);
      }
    } else {
      for (int64_t i = 0; i < *in_block; ++i) {
        absl::StatusOr<int64_t> tag = in_.IntIn("a node tag", 1, kMaxCount);
        if (!tag.ok()) return tag.status();
        node_tags_[next + i] = *tag;
      }
      for (int64_t i = 0; i < *in_block; ++i) {
        for (double& x : points_[next + i]) {
          absl::StatusOr<double> value = in_.FiniteDouble("a node coordinate");
          if (!value.ok()) return value.status();
          x = *value;
        }
        for (int64_t p = 0; p < extra; ++p) {
          if (absl::Status s = in_.Double("a parametric coordinate").status(); !s.ok()) return s;
        }
      }
    }
    next += *in_block;
  }
  if (next != *count) {
    return in_.Error(absl::StrCat("node blocks hold ", next, " nodes, header says ", *count));
  }
  return FinishNodes();
}

absl::Status GmshParser::StartElements(int64_t count) {
  if (!have_nodes_) return in_.Error("$Elements before $Nodes");
  if (have_elements_) return in_.Error("second $Elements section");
  // An element is at least "t n" with separators: 4 bytes (more in binary).
  if (absl::Status s = in_.CheckCount(count, 4, "elements"); !s.ok()) return s;
  have_elements_ = true;
  return absl::OkStatus();
}

absl::Status GmshParser::CountOther(int64_t type, int64_t n) {
  if (NodesPerElement(type) == 0) return in_.Error(absl::StrCat("unknown element type ", type));
  other_types_[type] += n;
  return absl::OkStatus();
}

absl::Status GmshParser::Element(int64_t tag, int64_t type, const int64_t* nodes, int64_t label) {
  if (type != kGmshTet) return CountOther(type, 1);
  Tet tet;
  for (int k = 0; k < 4; ++k) {
    const uint32_t index = node_index_.Find(nodes[k]);
    if (index == TagMap::kNone) {
      return in_.Error(
          absl::StrCat("element ", tag, " uses node ", nodes[k], ", which is not defined"));
    }
    tet[k] = index;
  }
  if (label < std::numeric_limits<int32_t>::min() || label > std::numeric_limits<int32_t>::max()) {
    return in_.Error(absl::StrCat("element ", tag, ": physical tag ", label, " is not 32-bit"));
  }
  if (label != 0) any_physical_ = true;
  tets_.push_back(tet);
  tet_tags_.push_back(tag);
  labels_.push_back(static_cast<int32_t>(label));
  return absl::OkStatus();
}

absl::Status GmshParser::Elements22() {
  absl::StatusOr<int64_t> count = in_.IntIn("the element count", 0, kMaxCount);
  if (!count.ok()) return count.status();
  if (absl::Status s = StartElements(*count); !s.ok()) return s;
  int64_t nodes[125];
  if (binary_) {
    StartBinary();
    int64_t seen = 0;
    while (seen < *count) {
      absl::StatusOr<absl::string_view> header = Binary(3, 4, "an element block header");
      if (!header.ok()) return header.status();
      const int64_t type = Load<int32_t>(*header, 0);
      const int64_t in_block = Load<int32_t>(*header, 1);
      const int64_t ntags = Load<int32_t>(*header, 2);
      const int nn = NodesPerElement(type);
      if (nn == 0) return in_.Error(absl::StrCat("unknown element type ", type));
      if (in_block < 0 || in_block > *count - seen || ntags < 0 || ntags > 1024) {
        return in_.Error("corrupt binary element block header");
      }
      const int64_t width = 1 + ntags + nn;
      absl::StatusOr<absl::string_view> data = Binary(in_block * width, 4, "elements");
      if (!data.ok()) return data.status();
      if (type != kGmshTet) {
        if (absl::Status s = CountOther(type, in_block); !s.ok()) return s;
      } else {
        for (int64_t e = 0; e < in_block; ++e) {
          const size_t at = e * width;
          const int64_t physical = ntags > 0 ? Load<int32_t>(*data, at + 1) : 0;
          for (int k = 0; k < 4; ++k) nodes[k] = Load<int32_t>(*data, at + 1 + ntags + k);
          if (absl::Status s = Element(Load<int32_t>(*data, at), type, nodes, physical); !s.ok()) {
            return s;
          }
          entities22_.push_back(ntags > 1 ? Load<int32_t>(*data, at + 2) : 0);
        }
      }
      seen += in_block;
    }
    DropPhysicalCopies22();
    return absl::OkStatus();
  }
  for (int64_t i = 0; i < *count; ++i) {
    absl::StatusOr<int64_t> tag = in_.Int("an element tag");
    if (!tag.ok()) return tag.status();
    absl::StatusOr<int64_t> type = in_.Int("an element type");
    if (!type.ok()) return type.status();
    const int nn = NodesPerElement(*type);
    if (nn == 0) return in_.Error(absl::StrCat("unknown element type ", *type));
    absl::StatusOr<int64_t> tags = in_.IntIn("an element's tag count", 0, 1 << 16);
    if (!tags.ok()) return tags.status();
    int64_t physical = 0, entity = 0;
    for (int64_t k = 0; k < *tags; ++k) {
      absl::StatusOr<int64_t> value = in_.Int("an element tag");
      if (!value.ok()) return value.status();
      if (k == 0) physical = *value;
      if (k == 1) entity = *value;
    }
    for (int k = 0; k < nn; ++k) {
      absl::StatusOr<int64_t> node = in_.Int("an element node tag");
      if (!node.ok()) return node.status();
      nodes[k] = *node;
    }
    if (absl::Status s = Element(*tag, *type, nodes, physical); !s.ok()) return s;
    if (*type == kGmshTet) entities22_.push_back(entity);
  }
  DropPhysicalCopies22();
  return absl::OkStatus();
}

// Gmsh's MSH 2 writer repeats every element of an elementary entity that is in several physical
// groups, once per group, under new element tags. Read as they are, such a file held each tet
// twice: `info` reported twice the volume and an empty boundary, `refine` refused the copies as
// repeated tets. Like a Gmsh 4 file, whose entity lists its groups once, a tet keeps its first
// group's label and the other groups are named as not read. A copy is a later element of the
// same entity on the same nodes with another physical tag; one with the same tag is a real repeat
// and is left for the validation to name.
void GmshParser::DropPhysicalCopies22() {
  const size_t n = tets_.size();
  // Most files have one group per entity: nothing to look for.
  absl::flat_hash_map<int64_t, int32_t> entity_label;
  bool several = false;
  for (size_t i = 0; i < n && !several; ++i) {
    const auto [it, inserted] = entity_label.try_emplace(entities22_[i], labels_[i]);
    several = !inserted && it->second != labels_[i];
  }
  if (!several) return;
  // Each tet's key (entity, sorted nodes), made once rather than in every comparison.
  std::vector<std::pair<int64_t, Tet>> keys(n);
  for (size_t i = 0; i < n; ++i) {
    keys[i] = {entities22_[i], tets_[i]};
    std::sort(keys[i].second.begin(), keys[i].second.end());
  }
  const auto key = [&](uint32_t i) -> const std::pair<int64_t, Tet>& { return keys[i]; };
  std::vector<uint32_t> order(n);
  std::iota(order.begin(), order.end(), 0u);
  std::sort(order.begin(), order.end(),
            [&](uint32_t a, uint32_t b) { return key(a) != key(b) ? key(a) < key(b) : a < b; });
  std::vector<bool> drop(n, false);
  bool any = false;
  for (size_t g = 0; g < n;) {
    size_t end = g + 1;
    const auto& first = key(order[g]);
    while (end < n && key(order[end]) == first) ++end;
    for (size_t k = g + 1; k < end; ++k) {
      const uint32_t copy = order[k];
      if (labels_[copy] == labels_[order[g]]) continue;
      drop[copy] = any = true;
      const std::pair<int64_t, int64_t> group = {entities22_[copy], labels_[copy]};
      if (std::find(other_groups_.begin(), other_groups_.end(), group) == other_groups_.end()) {
        other_groups_.push_back(group);
      }
    }
    g = end;
  }
  if (!any) return;
  std::sort(other_groups_.begin(), other_groups_.end());
  size_t kept = 0;
  for (size_t i = 0; i < n; ++i) {
    if (drop[i]) continue;
    tets_[kept] = tets_[i];
    tet_tags_[kept] = tet_tags_[i];
    labels_[kept] = labels_[i];
    ++kept;
  }
  tets_.resize(kept);
  tet_tags_.resize(kept);
  labels_.resize(kept);
}

absl::Status GmshParser::Elements41() {
  StartBinary();
  absl::StatusOr<int64_t> blocks = Size("the element block count", 0, kMaxCount);
  if (!blocks.ok()) return blocks.status();
  absl::StatusOr<int64_t> count = Size("the element count", 0, kMaxCount);
  if (!count.ok()) return count.status();
  for (const char* what : {"the minimum element tag", "the maximum element tag"}) {
    if (absl::Status s = Size(what, 0, std::numeric_limits<int64_t>::max()).status(); !s.ok()) {
      return s;
    }
  }
  if (absl::Status s = StartElements(*count); !s.ok()) return s;
  ReserveHuge(tets_, std::min<int64_t>(*count, 1 << 26));
  ReserveHuge(tet_tags_, std::min<int64_t>(*count, 1 << 26));
  ReserveHuge(labels_, std::min<int64_t>(*count, 1 << 26));
  int64_t seen = 0;
  int64_t nodes[125];
  for (int64_t b = 0; b < *blocks; ++b) {
    absl::StatusOr<int64_t> dim = Int("an entity dimension", 0, 3);
    if (!dim.ok()) return dim.status();
    absl::StatusOr<int64_t> entity = Int("an entity tag", std::numeric_limits<int32_t>::min(),
                                         std::numeric_limits<int32_t>::max());
    if (!entity.ok()) return entity.status();
    absl::StatusOr<int64_t> type = Int("an element type", 0, 1 << 16);
    if (!type.ok()) return type.status();
    absl::StatusOr<int64_t> in_block = Size("a block's element count", 0, *count - seen);
    if (!in_block.ok()) return in_block.status();
    const int nn = NodesPerElement(*type);
    if (nn == 0) return in_.Error(absl::StrCat("unknown element type ", *type));
    int64_t physical = 0;
    if (const auto it = entity_physical_.find((*dim << 32) + *entity);
        it != entity_physical_.end()) {
      physical = it->second;
    }
    if (*type == kGmshTet && *in_block > 0) tet_entities41_.insert(*entity);
    if (binary_) {
      absl::StatusOr<absl::string_view> data = Binary(*in_block * (1 + nn), 8, "elements");
      if (!data.ok()) return data.status();
      if (*type != kGmshTet) {
        if (absl::Status s = CountOther(*type, *in_block); !s.ok()) return s;
      } else {
        for (int64_t e = 0; e < *in_block; ++e) {
          const size_t at = e * (1 + nn);
          // Tags beyond int64 cannot name a node; -1 is reported as undefined.
          const auto tag = [&](size_t i) {
            const uint64_t t = Load<uint64_t>(*data, i);
            return t > static_cast<uint64_t>(kMaxCount) ? int64_t{-1} : static_cast<int64_t>(t);
          };
          for (int k = 0; k < 4; ++k) nodes[k] = tag(at + 1 + k);
          if (absl::Status s = Element(tag(at), *type, nodes, physical); !s.ok()) return s;
        }
      }
    } else {
      for (int64_t e = 0; e < *in_block; ++e) {
        absl::StatusOr<int64_t> tag = in_.Int("an element tag");
        if (!tag.ok()) return tag.status();
        for (int k = 0; k < nn; ++k) {
          absl::StatusOr<int64_t> node = in_.Int("an element node tag");
          if (!node.ok()) return node.status();
          nodes[k] = *node;
        }
        if (absl::Status s = Element(*tag, *type, nodes, physical); !s.ok()) return s;
      }
    }
    seen += *in_block;
  }
  if (seen != *count) {
    return in_.Error(absl::StrCat("element blocks hold ", seen, " elements, header says ", *count));
  }
  return absl::OkStatus();
}

// $NodeData / $ElementData: string tags (one per line, quoted), real tags, integer tags (time
// step, components, entity count, ...), then "tag value..." per entity (binary: int32 tag and
// doubles).
absl::Status GmshParser::Data(bool node_data) {
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
  if (absl::Status s = in_.CheckCount(entities, binary_ ? 4 + 8 * components : 2 * (1 + components),
                                      "data entries");
      !s.ok()) {
    return s;
  }
  std::vector<double>* target = nullptr;
  if (components == 1) {
    if (node_data && name == "value") {
      values_.assign(points_.size(), std::nan(""));
      target = &values_;
    } else if (!node_data && (name == "iteration" || name == "quality")) {
      target = name == "iteration" ? &iteration_ : &quality_;
      target->assign(tets_.size(), std::nan(""));
    }
  }
  absl::string_view block;
  if (binary_) {
    StartBinary();
    absl::StatusOr<absl::string_view> bytes = Binary(entities, 4 + 8 * components, "data entries");
    if (!bytes.ok()) return bytes.status();
    block = *bytes;
  }
  for (int64_t i = 0; i < entities; ++i) {
    int64_t tag;
    if (binary_) {
      tag = LoadAs<int32_t>(block, i * (4 + 8 * components), order_);
    } else {
      absl::StatusOr<int64_t> t = in_.Int("a data entity tag");
      if (!t.ok()) return t.status();
      tag = *t;
    }
    for (int64_t c = 0; c < components; ++c) {
      double value;
      if (binary_) {
        value = LoadAs<double>(block, i * (4 + 8 * components) + 4 + 8 * c, order_);
      } else {
        absl::StatusOr<double> v = in_.Double("a data value");
        if (!v.ok()) return v.status();
        value = *v;
      }
      if (target == nullptr) continue;
      uint32_t index;
      if (node_data) {
        index = node_index_.Find(tag);
        if (index == TagMap::kNone) {
          return in_.Error(absl::StrCat("$NodeData names node ", tag, ", which is not defined"));
        }
      } else {
        index = tet_index_.Find(tag);
        if (index == TagMap::kNone) continue;  // data of a skipped (non-tet) element
      }
      if (std::isnan(value)) return in_.Error(absl::StrCat("value of entity ", tag, " is NaN"));
      (*target)[index] = value;
    }
  }
  return absl::OkStatus();
}

absl::StatusOr<MeshFile> GmshParser::Parse(GmshReadInfo* info) {
  if (absl::Status s = MeshFormat(); !s.ok()) return s;
  while (!in_.AtEnd()) {
    absl::StatusOr<absl::string_view> token = in_.Token("a section");
    if (!token.ok()) return token.status();
    absl::string_view section = *token;
    if (!absl::ConsumePrefix(&section, "$")) {
      return in_.Error(absl::StrCat("expected a $Section, got ", QuoteToken(*token)));
    }
    const std::string name(section);
    absl::Status s;
    if (name == "ParametricNodes") {
      // MSH 2 files saved with Mesh.SaveParametric hold their nodes here instead of $Nodes; they
      // were refused as "$Elements before $Nodes" (found by a file-format sweep).
      return in_.Error(
          "$ParametricNodes (MSH 2 nodes with parametric coordinates) is not read: save the mesh "
          "without Mesh.SaveParametric, or as MSH 4.1");
    }
    if (name == "Nodes") {
      s = version_ >= 4 ? Nodes41() : Nodes22();
    } else if (name == "Elements") {
      s = version_ >= 4 ? Elements41() : Elements22();
      if (s.ok()) {
        if (const int64_t repeated = tet_index_.Build(tet_tags_); repeated != 0) {
          s = in_.Error(absl::StrCat("element tag ", repeated, " repeats"));
        }
      }
    } else if (name == "Entities" && version_ >= 4) {
      s = Entities();
    } else if (name == "PartitionedEntities" && version_ >= 4) {
      s = PartitionedEntities();
    } else if (name == "PhysicalNames") {
      s = PhysicalNames();
    } else if (name == "NodeData" || name == "ElementData") {
      s = Data(name == "NodeData");
    } else {
      s = SkipSection(name);
      if (s.ok()) continue;
    }
    if (!s.ok()) return s;
    if (absl::Status end = ExpectEnd(name); !end.ok()) return end;
  }
  return Finish(info);
}

absl::StatusOr<MeshFile> GmshParser::Finish(GmshReadInfo* info) {
  if (!have_nodes_ || !have_elements_) {
    return in_.Error("truncated or incomplete: $Nodes and $Elements are both required");
  }
  CellCensus census;
  census.AddTets(static_cast<int64_t>(tets_.size()));
  int64_t skipped = 0;
  for (const auto& [type, n] : other_types_) {
    const CellKind kind = GmshCellKind(type);
    census.Add(kind, n);
    if (kind.fate == CellFate::kSkip) skipped += n;
  }
  if (absl::Status s = census.Check(path_); !s.ok()) return s;
  if (info != nullptr) info->ignored_elements = skipped;
  const auto missing = [](const std::vector<double>& a) {
    return std::count_if(a.begin(), a.end(), [](double x) { return std::isnan(x); });
  };
  if (const int64_t m = missing(values_); m > 0) {
    return in_.Error(
        absl::StrCat("$NodeData \"value\" misses ", m, " of ", values_.size(), " nodes"));
  }
  for (const auto& [name, array] :
       {std::pair{"iteration", &iteration_}, std::pair{"quality", &quality_}}) {
    if (const int64_t m = missing(*array); m > 0) {
      return in_.Error(absl::StrCat("$ElementData \"", name, "\" misses ", m, " of ", array->size(),
                                    " tetrahedra"));
    }
  }
  for (double it : iteration_) {
    if (it != std::floor(it) || it < std::numeric_limits<int32_t>::min() ||
        it > std::numeric_limits<int32_t>::max()) {
      return in_.Error(absl::StrCat("iteration ", it, " is not a 32-bit integer"));
    }
  }
  // A quality that is not a finite float is kept as NaN: DropNonFiniteDerivedArrays drops the
  // array, not the mesh.
  for (double& q : quality_) {
    if (!std::isfinite(q) || std::abs(q) > std::numeric_limits<float>::max()) {
      q = std::numeric_limits<double>::quiet_NaN();
    }
  }
  // Tets in element-tag order: a writer may list elements in another order than their tags
  // (FormatGmsh41 numbers them in the order it writes them; Gmsh's own files are in tag order).
  const size_t t = tets_.size();
  std::vector<uint32_t> order;
  if (!std::is_sorted(tet_tags_.begin(), tet_tags_.end())) {
    order.resize(t);
    std::iota(order.begin(), order.end(), 0u);
    std::sort(order.begin(), order.end(),
              [&](uint32_t a, uint32_t b) { return tet_tags_[a] < tet_tags_[b]; });
  }
  const auto at = [&](size_t i) { return order.empty() ? i : order[i]; };
  MeshFile file;
  file.skipped_cells = census.SkippedCells();
  file.mesh.points = std::move(points_);
  file.mesh.values = std::move(values_);
  ReserveHuge(file.mesh.tets, t);
  file.mesh.tets.resize(t);
  for (size_t i = 0; i < t; ++i) file.mesh.tets[i] = tets_[at(i)];
  if (!iteration_.empty()) {
    file.tet_iteration.resize(t);
    for (size_t i = 0; i < t; ++i) file.tet_iteration[i] = static_cast<int32_t>(iteration_[at(i)]);
  }
  if (!quality_.empty()) {
    file.tet_quality.resize(t);
    for (size_t i = 0; i < t; ++i) file.tet_quality[i] = static_cast<float>(quality_[at(i)]);
  }
  if (any_physical_) {
    file.mesh.labels.resize(t);
    for (size_t i = 0; i < t; ++i) file.mesh.labels[i] = labels_[at(i)];
    file.label_name = "gmsh:physical";
    // A Gmsh 4 volume in two physical groups (a "ball" inside an "everything") lost the second
    // without a word: the output had only the first.
    if (!other_groups_.empty()) {
      const std::string listed = FirstFewJoined(other_groups_, [&](const auto& entity_group) {
        const auto& [entity, group] = entity_group;
        const auto name = region_names_.find(static_cast<int32_t>(group));
        return absl::StrCat(
            group, name == region_names_.end() ? "" : absl::StrCat(" (\"", name->second, "\")"),
            " of volume ", entity);
      });
      file.dropped_arrays.push_back(
          absl::StrCat("physical group", other_groups_.size() == 1 ? " " : "s ", listed,
                       " (a tet keeps one label: its volume's first physical group)"));
    }
    file.region_names = std::move(region_names_);
  } else {
    // Without physical groups Gmsh's elementary volumes are the only regions the file has, and
    // they were merged into one without a word (an outside review: two boxes meshed without
    // `Physical Volume` came out unlabelled). They are named as not carried; labels stay the
    // physical groups', as every other reader and writer of Gmsh files takes them.
    std::set<int64_t> entities = tet_entities41_;
    // A set insertion per tet only where the entity changes: Gmsh writes an entity's tets in a
    // run, so this is one per volume, not one per tet (2.2 files; 4.1 lists entities per block).
    for (size_t i = 0; i < entities22_.size(); ++i) {
      if (i == 0 || entities22_[i] != entities22_[i - 1]) entities.insert(entities22_[i]);
    }
    if (entities.size() > 1) {
      file.dropped_arrays.push_back(absl::StrCat(
          "elementary volumes ",
          FirstFewJoined(entities, [](int64_t entity) { return absl::StrCat(entity); }),
          " as regions (the file has no physical groups, so its tets are one region: a "
          "Physical Volume for each keeps them apart)"));
    }
  }
  DropNonFiniteDerivedArrays(&file);
  if (absl::Status s = ValidateMeshFile(file, path_); !s.ok()) return s;
  return file;
}

}  // namespace

absl::StatusOr<MeshFile> ParseGmsh(absl::string_view text, absl::string_view path,
                                   GmshReadInfo* info) {
  GmshParser parser(text, path);
  return parser.Parse(info);
}

}  // namespace tetrefine::io
