// Writing Gmsh .msh 4.1, ASCII or binary. See gmsh_format.h for the layout.
#include <algorithm>
#include <cstring>
#include <numeric>
#include <string>
#include <utility>
#include <vector>

#include "absl/container/flat_hash_map.h"
#include "absl/strings/str_cat.h"
#include "client/io/gmsh_format.h"
#include "client/io/number_text.h"
#include "core/huge_pages.h"

namespace tetrefine::io {
namespace {

// Appends values in the machine's byte order: binary .msh is native, and its endianness word
// tells readers which order that was.
template <typename T>
void AppendNative(std::string& out, const T* values, size_t n) {
  if (n > 0) out.append(reinterpret_cast<const char*>(values), n * sizeof(T));
}

// Fixed-size records appended through a small buffer: no temporary the size of the section,
// no zero-filling of `out` before it is written.
class RecordWriter {
 public:
  explicit RecordWriter(std::string& out) : out_(out) {}
  ~RecordWriter() { Flush(); }
  template <typename T>
  void Put(T value) {
    if (used_ + sizeof(T) > sizeof(buffer_)) Flush();
    std::memcpy(buffer_ + used_, &value, sizeof(T));
    used_ += sizeof(T);
  }
  void Flush() {
    out_.append(buffer_, used_);
    used_ = 0;
  }

 private:
  std::string& out_;
  char buffer_[1 << 16];
  size_t used_ = 0;
};
template <typename T>
void AppendNative(std::string& out, T value) {
  AppendNative(out, &value, 1);
}

// The tets of one volume entity: a label and the tet indices carrying it, in order.
struct Group {
  int32_t label = 0;
  std::vector<uint32_t> tets;
  Vec3 lo{0, 0, 0};
  Vec3 hi{0, 0, 0};
};

std::vector<Group> GroupByLabel(const MeshFile& file) {
  const Mesh& mesh = file.mesh;
  const size_t t = mesh.tets.size();
  std::vector<Group> groups;
  if (file.mesh.labels.empty()) {
    groups.resize(1);
    groups[0].tets.resize(t);
    for (size_t i = 0; i < t; ++i) groups[0].tets[i] = static_cast<uint32_t>(i);
  } else {
    absl::flat_hash_map<int32_t, size_t> index;  // label -> group
    for (int32_t label : file.mesh.labels) index.emplace(label, 0);
    std::vector<int32_t> labels;
    for (const auto& [label, g] : index) labels.push_back(label);
    std::sort(labels.begin(), labels.end());  // groups (entities) in label order
    for (int32_t label : labels) {
      index[label] = groups.size();
      groups.emplace_back();
      groups.back().label = label;
    }
    size_t g = 0;
    int32_t last = labels.front();
    for (size_t i = 0; i < t; ++i) {
      const int32_t label = file.mesh.labels[i];
      if (label != last) {  // labels come in runs; look up only where they change
        g = index[label];
        last = label;
      }
      groups[g].tets.push_back(static_cast<uint32_t>(i));
    }
  }
  for (Group& g : groups) {
    bool first = true;
    for (uint32_t i : g.tets) {
      for (uint32_t v : mesh.tets[i]) {
        for (int a = 0; a < 3; ++a) {
          const double x = mesh.points[v][a];
          g.lo[a] = first ? x : std::min(g.lo[a], x);
          g.hi[a] = first ? x : std::max(g.hi[a], x);
        }
        first = false;
      }
    }
  }
  return groups;
}

void AppendText(std::string& out, double x) { AppendDouble(out, x); }

// The ASCII header of a $NodeData / $ElementData section.
void AppendDataHeader(std::string& out, const char* section, const char* name, size_t count) {
  absl::StrAppend(&out, "$", section, "\n1\n\"", name, "\"\n1\n0\n3\n0\n1\n", count, "\n");
}

// Entry k is values[order(k)] under tag k + 1, for k < n.
template <typename T, typename Order>
void AppendData(std::string& out, const char* section, const char* name, const T* values, size_t n,
                bool binary, Order order) {
  AppendDataHeader(out, section, name, n);
  if (binary) {
    {
      RecordWriter w(out);
      for (size_t k = 0; k < n; ++k) {
        w.Put(static_cast<int32_t>(k + 1));
        w.Put(static_cast<double>(values[order(k)]));
      }
    }
    out += '\n';
  } else {
    for (size_t k = 0; k < n; ++k) {
      const size_t i = order(k);
      absl::StrAppend(&out, k + 1, " ");
      if constexpr (std::is_same_v<T, double>) {
        AppendDouble(out, values[i]);
      } else if constexpr (std::is_same_v<T, float>) {
        AppendFloat(out, values[i]);
      } else {
        absl::StrAppend(&out, values[i]);
      }
      out += '\n';
    }
  }
  absl::StrAppend(&out, "$End", section, "\n");
}

}  // namespace

std::string FormatGmsh41(const MeshFile& file, const GmshWriteOptions& options) {
  const Mesh& mesh = file.mesh;
  const size_t v = mesh.points.size();
  const size_t t = mesh.tets.size();
  const bool binary = options.binary;
  const std::vector<Group> groups = GroupByLabel(file);

  std::string out = absl::StrCat("$MeshFormat\n4.1 ", binary ? 1 : 0, " 8\n");
  // Binary sizes are known; text takes about as much again per number. Per group: its entity
  // (72 bytes in binary), its element block's header (20) and its name's line. 80 bytes a group
  // was short of that, and a mesh of many labels then copied its file into a doubled buffer.
  size_t names_bytes = 0;
  for (const auto& [label, name] : file.region_names) names_bytes += 32 + name.size();
  ReserveHuge(out, 1024 + 128 * groups.size() + names_bytes + v * (8 + 24 + 12) + t * (40 + 24) +
                       (binary ? 0 : v * 40 + t * 20));
  if (binary) {
    AppendNative<int32_t>(out, 1);
    out += '\n';
  }
  out += "$EndMeshFormat\n";
  // Every label of a labelled mesh is a physical group, zero and negative ones included. Gmsh
  // 4.8 reads and saves such tags as they are, and meshio needs one on every entity: with
  // entities left without a tag for labels <= 0 (as before 2026-11-25), meshio 5 refused the
  // file when labels mixed <= 0 and > 0 ("Incompatible cell data 'gmsh:physical'"), negative
  // labels came back as 0, and a Gmsh re-save, which keeps only elements in physical groups,
  // dropped the untagged tets. An unlabelled mesh has one entity without physical group.
  const bool physical = !mesh.labels.empty();
  // The names of the physical groups written (labels present in the mesh).
  std::vector<std::pair<int32_t, std::string>> names;
  for (const Group& group : groups) {
    auto name = file.region_names.find(group.label);
    if (physical && name != file.region_names.end()) names.emplace_back(*name);
  }
  if (!names.empty()) {
    absl::StrAppend(&out, "$PhysicalNames\n", names.size(), "\n");
    for (const auto& [label, name] : names) absl::StrAppend(&out, "3 ", label, " \"", name, "\"\n");
    out += "$EndPhysicalNames\n";
  }
  out += "$Entities\n";
  if (binary) {
    for (uint64_t n : {uint64_t{0}, uint64_t{0}, uint64_t{0}, uint64_t{groups.size()}}) {
      AppendNative(out, n);
    }
  } else {
    absl::StrAppend(&out, "0 0 0 ", groups.size(), "\n");
  }
  for (size_t g = 0; g < groups.size(); ++g) {
    const Group& group = groups[g];
    if (binary) {
      AppendNative<int32_t>(out, static_cast<int32_t>(g + 1));
      for (int a = 0; a < 3; ++a) AppendNative(out, group.lo[a]);
      for (int a = 0; a < 3; ++a) AppendNative(out, group.hi[a]);
      AppendNative<uint64_t>(out, physical ? 1 : 0);
      if (physical) AppendNative<int32_t>(out, group.label);
      AppendNative<uint64_t>(out, 0);  // no bounding surfaces
    } else {
      absl::StrAppend(&out, g + 1);
      for (double x :
           {group.lo[0], group.lo[1], group.lo[2], group.hi[0], group.hi[1], group.hi[2]}) {
        out += ' ';
        AppendText(out, x);
      }
      if (physical) {
        absl::StrAppend(&out, " 1 ", group.label, " 0\n");
      } else {
        out += " 0 0\n";
      }
    }
  }
  if (binary) out += '\n';
  out += "$EndEntities\n$Nodes\n";
  // All nodes in volume entity 1: Gmsh and meshio accept nodes on any entity.
  const uint64_t node_blocks = v == 0 ? 0 : 1;
  if (binary) {
    for (uint64_t n : {node_blocks, uint64_t{v}, uint64_t{v == 0 ? 0u : 1u}, uint64_t{v}}) {
      AppendNative(out, n);
    }
    if (v > 0) {
      AppendNative<int32_t>(out, 3);
      AppendNative<int32_t>(out, 1);
      AppendNative<int32_t>(out, 0);
      AppendNative<uint64_t>(out, v);
      {
        RecordWriter w(out);
        for (size_t i = 0; i < v; ++i) w.Put(uint64_t{i + 1});
      }
      static_assert(sizeof(Vec3) == 3 * sizeof(double));
      AppendNative(out, mesh.points.empty() ? nullptr : mesh.points[0].data(), 3 * v);
    }
    out += '\n';
  } else {
    absl::StrAppend(&out, node_blocks, " ", v, " ", v == 0 ? 0 : 1, " ", v, "\n");
    if (v > 0) {
      absl::StrAppend(&out, "3 1 0 ", v, "\n");
      for (size_t i = 1; i <= v; ++i) absl::StrAppend(&out, i, "\n");
      for (const Vec3& p : mesh.points) {
        AppendText(out, p[0]);
        out += ' ';
        AppendText(out, p[1]);
        out += ' ';
        AppendText(out, p[2]);
        out += '\n';
      }
    }
  }
  out += "$EndNodes\n$Elements\n";
  size_t element_blocks = 0;
  for (const Group& g : groups) element_blocks += g.tets.empty() ? 0 : 1;
  if (binary) {
    for (uint64_t n :
         {uint64_t{element_blocks}, uint64_t{t}, uint64_t{t == 0 ? 0u : 1u}, uint64_t{t}}) {
      AppendNative(out, n);
    }
  } else {
    absl::StrAppend(&out, element_blocks, " ", t, " ", t == 0 ? 0 : 1, " ", t, "\n");
  }
  // Element tags are 1..T in the order written, and the element data follow that order: Gmsh
  // goes by the tags, but meshio takes data entries by position (and, in binary, refuses tags
  // other than 1..T in order). Until 2026-11-25 the tag was the tet's index, so the tet order
  // survived a round trip, but a file whose labels were not in ascending runs showed meshio
  // each tet's quality and iteration on another tet (off by up to 0.71) or was refused.
  uint64_t tag = 0;
  for (size_t g = 0; g < groups.size(); ++g) {
    const std::vector<uint32_t>& tets = groups[g].tets;
    if (tets.empty()) continue;
    if (binary) {
      AppendNative<int32_t>(out, 3);
      AppendNative<int32_t>(out, static_cast<int32_t>(g + 1));
      AppendNative<int32_t>(out, kGmshTet);
      AppendNative<uint64_t>(out, tets.size());
      RecordWriter w(out);
      for (uint32_t i : tets) {
        w.Put(++tag);
        for (uint32_t c : mesh.tets[i]) w.Put(uint64_t{c} + 1);
      }
    } else {
      absl::StrAppend(&out, "3 ", g + 1, " ", kGmshTet, " ", tets.size(), "\n");
      for (uint32_t i : tets) {
        const Tet& tet = mesh.tets[i];
        absl::StrAppend(&out, ++tag, " ", tet[0] + 1, " ", tet[1] + 1, " ", tet[2] + 1, " ",
                        tet[3] + 1, "\n");
      }
    }
  }
  if (binary) out += '\n';
  out += "$EndElements\n";
  if (!mesh.values.empty()) {
    AppendData(out, "NodeData", "value", mesh.values.data(), v, binary, [](size_t k) { return k; });
  }
  std::vector<uint32_t> element_order;  // tet index of element tag k + 1
  if (!file.tet_iteration.empty() || !file.tet_quality.empty()) {
    element_order.reserve(t);
    for (const Group& g : groups) {
      element_order.insert(element_order.end(), g.tets.begin(), g.tets.end());
    }
  }
  const auto in_element_order = [&](size_t k) { return static_cast<size_t>(element_order[k]); };
  if (!file.tet_iteration.empty()) {
    AppendData(out, "ElementData", "iteration", file.tet_iteration.data(), t, binary,
               in_element_order);
  }
  if (!file.tet_quality.empty()) {
    AppendData(out, "ElementData", "quality", file.tet_quality.data(), t, binary, in_element_order);
  }
  return out;
}

void OrderTetsAsGmshWrites(MeshFile& file) {
  if (file.mesh.labels.empty()) return;
  const std::vector<int32_t>& labels = file.mesh.labels;
  std::vector<size_t> order(file.mesh.tets.size());
  std::iota(order.begin(), order.end(), size_t{0});
  std::stable_sort(order.begin(), order.end(),
                   [&](size_t a, size_t b) { return labels[a] < labels[b]; });
  const auto permute = [&](auto& v) {
    if (v.empty()) return;
    const auto copy = v;
    for (size_t i = 0; i < order.size(); ++i) v[i] = copy[order[i]];
  };
  permute(file.mesh.tets);
  permute(file.mesh.labels);
  permute(file.tet_iteration);
  permute(file.tet_quality);
}

}  // namespace tetrefine::io
