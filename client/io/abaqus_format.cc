// Abaqus .inp. See abaqus_format.h.
#include "client/io/abaqus_format.h"

#include <cctype>
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <unordered_map>
#include <unordered_set>
#include <utility>
#include <vector>

#include "absl/strings/ascii.h"
#include "absl/strings/match.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_split.h"
#include "absl/strings/strip.h"
#include "client/io/cell_census.h"
#include "client/io/io_error.h"
#include "client/io/number_text.h"

namespace tetrefine::io {
namespace {

// A keyword line: "*ELEMENT, TYPE=C3D4, ELSET=Volume1" -> name "ELEMENT", params TYPE, ELSET.
struct Keyword {
  std::string name;                           // upper case
  std::map<std::string, std::string> params;  // upper-case key -> value as written
};

Keyword ParseKeyword(absl::string_view line) {
  Keyword k;
  std::vector<absl::string_view> parts = absl::StrSplit(line.substr(1), ',');
  k.name = absl::AsciiStrToUpper(absl::StripAsciiWhitespace(parts[0]));
  for (size_t i = 1; i < parts.size(); ++i) {
    const absl::string_view part = absl::StripAsciiWhitespace(parts[i]);
    const size_t eq = part.find('=');
    if (eq == absl::string_view::npos) {
      k.params[absl::AsciiStrToUpper(part)] = "";
    } else {
      k.params[absl::AsciiStrToUpper(absl::StripAsciiWhitespace(part.substr(0, eq)))] =
          std::string(absl::StripAsciiWhitespace(part.substr(eq + 1)));
    }
  }
  return k;
}

// What an element type is: a linear tet, another volume element, or something to skip.
enum class ElementClass { kTet, kOtherVolume, kSkip };

ElementClass Classify(const std::string& type) {
  // Continuum solids are [D|A]C3D<n><variant>: C3D4, C3D4H, DC3D4, C3D10M, C3D8R, ...
  absl::string_view t = type;
  absl::ConsumePrefix(&t, "D") || absl::ConsumePrefix(&t, "A");
  if (!absl::ConsumePrefix(&t, "C3D")) return ElementClass::kSkip;
  size_t digits = 0;
  while (digits < t.size() && absl::ascii_isdigit(t[digits])) ++digits;
  if (digits == 0) return ElementClass::kSkip;
  return t.substr(0, digits) == "4" ? ElementClass::kTet : ElementClass::kOtherVolume;
}

// The trailing number of a set name: "PhysicalVolume5" -> 5.
std::optional<int32_t> TrailingNumber(absl::string_view name) {
  size_t start = name.size();
  while (start > 0 && absl::ascii_isdigit(name[start - 1])) --start;
  int64_t value = 0;
  if (start == name.size() || name.size() - start > 9 || !ParseInt64(name.substr(start), value)) {
    return std::nullopt;
  }
  return static_cast<int32_t>(value);
}

class AbaqusParser {
 public:
  AbaqusParser(absl::string_view text, absl::string_view path) : path_(path) {
    lines_ = absl::StrSplit(text, '\n');
  }

  absl::StatusOr<MeshFile> Parse();

 private:
  absl::Status Error(int64_t line, absl::string_view problem) const {
    return FileLineError(path_, line + 1, problem);
  }
  // The next data line's comma-separated fields, with continuation lines (a line ending with a
  // comma) joined; false at a keyword line or the end. Comment and blank lines are skipped.
  bool NextRecord(std::vector<absl::string_view>& fields, int64_t& line);
  absl::Status ReadNodes();
  absl::Status ReadElements(const Keyword& k, int64_t keyword_line);
  absl::Status ReadSet(const Keyword& k, int64_t keyword_line);
  absl::Status AssignLabels(MeshFile& file);

  absl::string_view path_;
  std::vector<absl::string_view> lines_;
  size_t at_ = 0;  // the next line to look at
  MeshFile file_;
  std::unordered_map<int64_t, uint32_t> node_index_;
  std::unordered_map<int64_t, uint32_t> tet_index_;  // element id -> tet
  std::unordered_set<int64_t> other_elements_;       // ids of skipped elements
  CellCensus census_;
  // GENERATE ranges stay ranges until the labels are assigned: one line "1, 4000000000" must
  // not become 4e9 ids before it is known that the file defines so many elements.
  struct IdRange {
    int64_t first = 0, last = 0, step = 1;
  };
  struct ElementSet {
    std::string name;
    int64_t line = 0;
    std::vector<int64_t> ids;
    std::vector<IdRange> ranges;
  };
  std::vector<ElementSet> sets_;          // *ELSET blocks, in file order
  std::vector<ElementSet> element_sets_;  // ELSET= of *ELEMENT blocks
};

bool IsComment(absl::string_view line) { return absl::StartsWith(line, "**"); }

bool AbaqusParser::NextRecord(std::vector<absl::string_view>& fields, int64_t& line) {
  fields.clear();
  bool continued = false;
  while (at_ < lines_.size()) {
    const absl::string_view raw = absl::StripAsciiWhitespace(lines_[at_]);
    if (raw.empty() || IsComment(raw)) {
      ++at_;
      continue;
    }
    if (raw[0] == '*') return continued;  // a keyword ends the record (and the block)
    if (!continued) line = static_cast<int64_t>(at_);
    ++at_;
    absl::string_view body = raw;
    const bool more = absl::ConsumeSuffix(&body, ",");
    for (absl::string_view f : absl::StrSplit(body, ',')) {
      fields.push_back(absl::StripAsciiWhitespace(f));
    }
    if (!more) return true;
    continued = true;
  }
  return continued;
}

absl::Status AbaqusParser::ReadNodes() {
  std::vector<absl::string_view> f;
  int64_t line = 0;
  while (NextRecord(f, line)) {
    int64_t id = 0;
    Vec3 p{0, 0, 0};
    if (f.size() != 4 || !ParseInt64(f[0], id)) {
      return Error(line, absl::StrCat("*NODE line has ", f.size(),
                                      " fields: expected \"id, x, y, z\" (a 3D mesh)"));
    }
    for (int a = 0; a < 3; ++a) {
      if (!ParseDouble(f[1 + a], p[a]) || !std::isfinite(p[a])) {
        return Error(line, absl::StrCat("node ", id, ": coordinate \"", f[1 + a].substr(0, 30),
                                        "\" is not a finite number"));
      }
    }
    if (file_.mesh.points.size() >= (size_t{1} << 32) - 1) {
      return Error(line, "more than 2^32 - 1 nodes");
    }
    if (!node_index_.emplace(id, static_cast<uint32_t>(file_.mesh.points.size())).second) {
      return Error(line, absl::StrCat("node ", id, " is defined twice"));
    }
    file_.mesh.points.push_back(p);
  }
  return absl::OkStatus();
}

absl::Status AbaqusParser::ReadElements(const Keyword& k, int64_t keyword_line) {
  const auto type = k.params.find("TYPE");
  if (type == k.params.end() || type->second.empty()) {
    return Error(keyword_line, "*ELEMENT without TYPE=");
  }
  const std::string type_name = absl::AsciiStrToUpper(type->second);
  const ElementClass kind = Classify(type_name);
  ElementSet set;
  if (const auto elset = k.params.find("ELSET"); elset != k.params.end()) {
    set.name = elset->second;
    set.line = keyword_line;
  }
  std::vector<absl::string_view> f;
  int64_t line = 0;
  int64_t count = 0;
  while (NextRecord(f, line)) {
    int64_t id = 0;
    if (f.empty() || !ParseInt64(f[0], id)) {
      return Error(line, "element line does not start with an element id");
    }
    if (tet_index_.count(id) > 0 || other_elements_.count(id) > 0) {
      return Error(line, absl::StrCat("element ", id, " is defined twice"));
    }
    ++count;
    if (!set.name.empty()) set.ids.push_back(id);
    if (kind != ElementClass::kTet) {
      other_elements_.insert(id);
      continue;
    }
    if (f.size() != 5) {
      return Error(line, absl::StrCat("element ", id, " of type ", type_name, " has ", f.size() - 1,
                                      " nodes, expected 4"));
    }
    Tet tet;
    for (int c = 0; c < 4; ++c) {
      int64_t node = 0;
      const auto it = ParseInt64(f[1 + c], node) ? node_index_.find(node) : node_index_.end();
      if (it == node_index_.end()) {
        return Error(line, absl::StrCat("element ", id, ": node \"", f[1 + c].substr(0, 30),
                                        "\" is not defined by an earlier *NODE"));
      }
      tet[c] = it->second;
    }
    tet_index_[id] = static_cast<uint32_t>(file_.mesh.tets.size());
    file_.mesh.tets.push_back(tet);
  }
  if (kind == ElementClass::kTet) {
    census_.AddTets(count);
  } else {
    census_.Add({absl::StrCat(type_name, " element"), absl::StrCat(type_name, " elements"),
                 kind == ElementClass::kOtherVolume ? CellFate::kUnsupported : CellFate::kSkip},
                count);
  }
  if (!set.name.empty()) element_sets_.push_back(std::move(set));
  return absl::OkStatus();
}

absl::Status AbaqusParser::ReadSet(const Keyword& k, int64_t keyword_line) {
  const auto name = k.params.find("ELSET");
  if (name == k.params.end() || name->second.empty()) {
    return Error(keyword_line, "*ELSET without ELSET=");
  }
  ElementSet set{name->second, keyword_line, {}, {}};
  const bool generate = k.params.count("GENERATE") > 0;
  std::vector<absl::string_view> f;
  int64_t line = 0;
  while (NextRecord(f, line)) {
    std::vector<int64_t> numbers;
    for (absl::string_view field : f) {
      if (field.empty()) continue;
      int64_t n = 0;
      if (!ParseInt64(field, n)) {
        return Error(line, absl::StrCat("*ELSET ", set.name, ": \"", field.substr(0, 30),
                                        "\" is not an element id (sets of sets are not read)"));
      }
      numbers.push_back(n);
    }
    if (!generate) {
      set.ids.insert(set.ids.end(), numbers.begin(), numbers.end());
      continue;
    }
    if (numbers.size() < 2 || numbers.size() > 3 || (numbers.size() == 3 && numbers[2] <= 0) ||
        numbers[1] < numbers[0] || numbers[1] - numbers[0] > (int64_t{1} << 32)) {
      return Error(line, absl::StrCat("*ELSET ", set.name,
                                      ", GENERATE: expected \"first, last[, step]\" with "
                                      "first <= last and step > 0"));
    }
    set.ranges.push_back({numbers[0], numbers[1], numbers.size() == 3 ? numbers[2] : 1});
  }
  sets_.push_back(std::move(set));
  return absl::OkStatus();
}

absl::Status AbaqusParser::AssignLabels(MeshFile& file) {
  const std::vector<ElementSet>& sets = sets_.empty() ? element_sets_ : sets_;
  std::vector<int32_t> region(file.mesh.tets.size(), -1);  // index into `taken`, -1: none
  std::vector<const ElementSet*> taken;
  for (const ElementSet& set : sets) {
    std::vector<uint32_t> tets;
    bool overlaps = false;
    const auto take = [&](int64_t id) -> absl::Status {
      const auto it = tet_index_.find(id);
      if (it == tet_index_.end()) {
        if (other_elements_.count(id) == 0) {
          return Error(set.line, absl::StrCat("element set ", set.name, " names element ", id,
                                              ", which the file does not define"));
        }
        return absl::OkStatus();
      }
      tets.push_back(it->second);
      if (region[it->second] >= 0) overlaps = true;
      return absl::OkStatus();
    };
    for (int64_t id : set.ids) {
      if (absl::Status s = take(id); !s.ok()) return s;
    }
    // A range longer than the file's element count names an element it does not define; the
    // walk below stops at the first such id, after at most that many steps.
    for (const IdRange& r : set.ranges) {
      for (int64_t id = r.first; id <= r.last; id += r.step) {
        if (absl::Status s = take(id); !s.ok()) return s;
      }
    }
    if (tets.empty() || overlaps) continue;
    for (uint32_t t : tets) region[t] = static_cast<int32_t>(taken.size());
    taken.push_back(&set);
  }
  if (taken.empty()) return absl::OkStatus();
  // Labels: the sets' trailing numbers when they are distinct and not 0, else 1, 2, ...
  std::vector<int32_t> label(taken.size());
  std::map<int32_t, int> seen;
  bool numbered = true;
  for (size_t i = 0; i < taken.size(); ++i) {
    const std::optional<int32_t> n = TrailingNumber(taken[i]->name);
    if (!n || *n == 0 || !seen.emplace(*n, 1).second) numbered = false;
    label[i] = n.value_or(0);
  }
  for (size_t i = 0; i < taken.size(); ++i) {
    if (!numbered) label[i] = static_cast<int32_t>(i + 1);
    std::string name;
    for (char c : taken[i]->name) {
      if (c != '"' && static_cast<unsigned char>(c) >= 0x20) name += c;
    }
    file.region_names[label[i]] = name;
  }
  file.mesh.labels.resize(file.mesh.tets.size());
  for (size_t t = 0; t < region.size(); ++t) {
    file.mesh.labels[t] = region[t] < 0 ? 0 : label[region[t]];
  }
  return absl::OkStatus();
}

absl::StatusOr<MeshFile> AbaqusParser::Parse() {
  while (at_ < lines_.size()) {
    const absl::string_view raw = absl::StripAsciiWhitespace(lines_[at_]);
    const int64_t line = static_cast<int64_t>(at_);
    ++at_;
    if (raw.empty() || IsComment(raw)) continue;
    if (raw[0] != '*') {
      return Error(line, "data line outside any keyword block");
    }
    const Keyword k = ParseKeyword(raw);
    if (k.name == "PART" || k.name == "INSTANCE" || k.name == "ASSEMBLY") {
      return FileUnsupported(
          path_, absl::StrCat("line ", line + 1, ": *", k.name,
                              ": Abaqus/CAE parts and instances (each with its own numbering "
                              "and transform) are not read; write a flat input (Gmsh or "
                              "meshio write one)"));
    }
    if (k.name == "INCLUDE") {
      return FileUnsupported(path_, absl::StrCat("line ", line + 1,
                                                 ": *INCLUDE is not followed; put the included "
                                                 "file's lines in its place"));
    }
    absl::Status s;
    if (k.name == "NODE") {
      s = ReadNodes();
    } else if (k.name == "ELEMENT") {
      s = ReadElements(k, line);
    } else if (k.name == "ELSET") {
      s = ReadSet(k, line);
    } else {
      // Anything else (HEADING's title, NSET, MATERIAL, STEP, ...): its data lines are skipped.
      while (at_ < lines_.size()) {
        const absl::string_view next = absl::StripAsciiWhitespace(lines_[at_]);
        if (!next.empty() && next[0] == '*' && !IsComment(next)) break;
        ++at_;
      }
    }
    if (!s.ok()) return s;
  }
  if (absl::Status s = census_.Check(path_); !s.ok()) return s;
  MeshFile file = std::move(file_);
  if (absl::Status s = AssignLabels(file); !s.ok()) return s;
  return file;
}

}  // namespace

absl::StatusOr<MeshFile> ParseAbaqus(absl::string_view text, absl::string_view path) {
  return AbaqusParser(text, path).Parse();
}

}  // namespace tetrefine::io
