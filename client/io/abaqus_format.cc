// Abaqus .inp. See abaqus_format.h.
#include "client/io/abaqus_format.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <deque>
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

// GENERATE ranges stay ranges until the labels are assigned: one line "1, 4000000000" must not
// become 4e9 ids before it is known that the file defines so many elements.
struct IdRange {
  int64_t first = 0, last = 0, step = 1;
};

struct ElementSet {
  std::string name;
  int64_t line = 0;
  std::vector<int64_t> ids;
  std::vector<IdRange> ranges;
  std::string instance;  // an assembly's set: the INSTANCE= it names (upper case)
  // Earlier sets this one names ("*ELSET, ELSET=All" over "Core3, Rim8"), walked when the labels
  // are assigned rather than copied here: sets that each name the one before twice would double
  // with every line.
  std::vector<const ElementSet*> members;
};

// The nodes, elements and sets of one *PART block, or of a flat file (name empty): each part has
// its own node and element numbering.
struct Part {
  std::string name;  // as written
  int64_t line = 0;  // of *PART; for the flat file's, of its first *ELEMENT
  std::vector<Vec3> points;
  std::vector<Tet> tets;
  std::unordered_map<int64_t, uint32_t> node_index;
  std::unordered_map<int64_t, uint32_t> tet_index;  // element id -> tet
  std::unordered_set<int64_t> other_elements;       // ids of skipped elements
  // Deques: sets point to the earlier sets they name.
  std::deque<ElementSet> sets;          // *ELSET blocks, in file order
  std::deque<ElementSet> element_sets;  // ELSET= of *ELEMENT blocks
  // The latest set of each upper-case name, for sets that name sets.
  std::unordered_map<std::string, const ElementSet*> sets_named, element_sets_named;
};

// An *INSTANCE of a part in the *ASSEMBLY: its nodes moved by the translation, then rotated by
// `degrees` about the axis from axis_a to axis_b (right-handed), as Abaqus places them.
struct Instance {
  std::string name;  // as written
  int64_t line = 0;
  size_t part = 0;
  Vec3 translation{0, 0, 0};
  bool rotated = false;
  Vec3 axis_a{0, 0, 0}, axis_b{0, 0, 0};
  double degrees = 0.0;
};

// The most nodes, and the most tets, an assembly's instances may place together (2^28: more
// than a refinement service admits by default, 10 M tets).
constexpr uint64_t kMaxPlaced = uint64_t{1} << 28;
constexpr int64_t kMaxWalkedIds = int64_t{1} << 28;

// Rotation of p by `degrees` about the axis through a and b (Rodrigues' formula).
Vec3 Rotate(const Vec3& p, const Vec3& a, const Vec3& b, double degrees) {
  Vec3 k{b[0] - a[0], b[1] - a[1], b[2] - a[2]};
  const double length = std::sqrt(k[0] * k[0] + k[1] * k[1] + k[2] * k[2]);
  for (double& x : k) x /= length;
  const double angle = degrees * (3.14159265358979323846 / 180.0);
  const double c = std::cos(angle), s = std::sin(angle);
  const Vec3 v{p[0] - a[0], p[1] - a[1], p[2] - a[2]};
  const Vec3 cross{k[1] * v[2] - k[2] * v[1], k[2] * v[0] - k[0] * v[2], k[0] * v[1] - k[1] * v[0]};
  const double dot = k[0] * v[0] + k[1] * v[1] + k[2] * v[2];
  Vec3 out;
  for (int i = 0; i < 3; ++i) out[i] = a[i] + v[i] * c + cross[i] * s + k[i] * dot * (1.0 - c);
  return out;
}

class AbaqusParser {
 public:
  AbaqusParser(absl::string_view text, absl::string_view path, const AbaqusIncludeReader& include)
      : text_(text), include_(include) {
    sources_.emplace_back(path);
    parts_.emplace_back();  // the flat file's nodes and elements
  }

  absl::StatusOr<MeshFile> Parse();

 private:
  // Where the keyword lines are: at the top, inside *PART, *ASSEMBLY or *INSTANCE.
  enum class Scope { kTop, kPart, kAssembly, kInstance };

  // `line` indexes lines_; the message names the file it came from and its line there.
  absl::Status Error(int64_t line, absl::string_view problem) const {
    const auto [source, number] = where_[static_cast<size_t>(line)];
    return FileLineError(sources_[source], number + 1, problem);
  }
  // Appends the lines of `text` (from sources_[source]) to lines_, each *INCLUDE replaced by the
  // lines of the file it names when include_ is set (else kept, and refused by Parse).
  absl::Status AddLines(absl::string_view text, uint32_t source, int depth);
  // The next data line's comma-separated fields, with continuation lines (a line ending with a
  // comma) joined; false at a keyword line or the end. Comment and blank lines are skipped.
  bool NextRecord(std::vector<absl::string_view>& fields, int64_t& line);
  void SkipData();
  absl::Status ReadNodes(Part& part);
  absl::Status ReadElements(Part& part, const Keyword& k, int64_t keyword_line);
  // `named` finds an earlier set by its upper-case name, or gives null.
  absl::Status ReadSet(const Keyword& k, int64_t keyword_line,
                       const std::function<const ElementSet*(const std::string&)>& named,
                       ElementSet& set);
  absl::Status OpenPart(const Keyword& k, int64_t line);
  absl::Status OpenInstance(const Keyword& k, int64_t line);
  absl::Status Structure(const Keyword& k, int64_t line, bool& handled);
  absl::StatusOr<MeshFile> Assemble();
  absl::Status AssignLabels(MeshFile& file, const std::vector<size_t>& placed,
                            const std::vector<uint32_t>& tet_offset);

  absl::string_view text_;
  const AbaqusIncludeReader& include_;
  std::vector<std::string> sources_;  // [0]: the file's own path, then the included files'
  std::deque<std::string> included_;  // the included files' text, which lines_ views
  int64_t included_bytes_ = 0;
  std::vector<absl::string_view> lines_;  // every line, included files' in place of *INCLUDE
  std::vector<std::pair<uint32_t, int64_t>> where_;  // per line: source and line number there
  size_t at_ = 0;                                    // the next line to look at
  Scope scope_ = Scope::kTop;
  std::vector<Part> parts_;                             // [0]: the flat file's
  size_t current_ = 0;                                  // the part being read
  std::unordered_map<std::string, size_t> part_named_;  // upper-case name -> part
  std::vector<Instance> instances_;
  std::unordered_map<std::string, size_t> instance_named_;  // upper-case name -> instance
  bool assembly_ = false;
  std::deque<ElementSet> assembly_sets_;  // *ELSET, INSTANCE=... in the assembly
  // The latest of them by "INSTANCE\nNAME" (upper case), for sets that name sets.
  std::unordered_map<std::string, const ElementSet*> assembly_sets_named_;
  CellCensus census_;
};

bool IsComment(absl::string_view line) { return absl::StartsWith(line, "**"); }

// How deep *INCLUDE may nest (a file that includes itself stops here), and how many bytes all
// inclusions may splice in together (a file naming a large one many times, or files that include
// each other several times each, would otherwise grow without bound before the depth limit).
constexpr int kMaxIncludeDepth = 8;
constexpr int64_t kMaxIncludedBytes = int64_t{1} << 32;

absl::Status AbaqusParser::AddLines(absl::string_view text, uint32_t source, int depth) {
  int64_t number = 0;
  for (absl::string_view line : absl::StrSplit(text, '\n')) {
    const absl::string_view raw = absl::StripAsciiWhitespace(line);
    const bool include = include_ && !raw.empty() && raw[0] == '*' && !IsComment(raw) &&
                         ParseKeyword(raw).name == "INCLUDE";
    if (!include) {
      lines_.push_back(line);
      where_.emplace_back(source, number++);
      continue;
    }
    const auto fail = [&](absl::string_view problem) {
      return FileLineError(sources_[source], number + 1, problem);
    };
    const Keyword k = ParseKeyword(raw);
    const auto input = k.params.find("INPUT");
    absl::string_view name;
    if (input != k.params.end()) name = input->second;
    if (name.size() >= 2 && name.front() == '"' && name.back() == '"') {
      name = name.substr(1, name.size() - 2);
    }
    if (name.empty()) return fail("*INCLUDE without INPUT=");
    if (depth >= kMaxIncludeDepth) {
      return fail(absl::StrCat("*INCLUDE nested more than ", kMaxIncludeDepth,
                               " deep (does a file include itself?)"));
    }
    absl::StatusOr<std::string> content = include_(name);
    if (!content.ok()) {
      return fail(absl::StrCat("*INCLUDE, INPUT=", name, ": ", content.status().message()));
    }
    included_bytes_ += static_cast<int64_t>(content->size());
    if (included_bytes_ > kMaxIncludedBytes) {
      return fail(absl::StrCat("*INCLUDE: the included files hold more than ", kMaxIncludedBytes,
                               " bytes together"));
    }
    included_.push_back(*std::move(content));
    sources_.emplace_back(name);
    if (absl::Status s =
            AddLines(included_.back(), static_cast<uint32_t>(sources_.size() - 1), depth + 1);
        !s.ok()) {
      return s;
    }
    ++number;
  }
  return absl::OkStatus();
}

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

void AbaqusParser::SkipData() {
  while (at_ < lines_.size()) {
    const absl::string_view next = absl::StripAsciiWhitespace(lines_[at_]);
    if (!next.empty() && next[0] == '*' && !IsComment(next)) break;
    ++at_;
  }
}

absl::Status AbaqusParser::ReadNodes(Part& part) {
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
    if (part.points.size() >= (size_t{1} << 32) - 1) {
      return Error(line, "more than 2^32 - 1 nodes");
    }
    if (!part.node_index.emplace(id, static_cast<uint32_t>(part.points.size())).second) {
      return Error(line, absl::StrCat("node ", id, " is defined twice"));
    }
    part.points.push_back(p);
  }
  return absl::OkStatus();
}

absl::Status AbaqusParser::ReadElements(Part& part, const Keyword& k, int64_t keyword_line) {
  const auto type = k.params.find("TYPE");
  if (type == k.params.end() || type->second.empty()) {
    return Error(keyword_line, "*ELEMENT without TYPE=");
  }
  const std::string type_name = absl::AsciiStrToUpper(type->second);
  const ElementClass kind = Classify(type_name);
  if (part.name.empty() && part.tets.empty() && part.other_elements.empty()) {
    part.line = keyword_line;
  }
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
    if (part.tet_index.count(id) > 0 || part.other_elements.count(id) > 0) {
      return Error(line, absl::StrCat("element ", id, " is defined twice"));
    }
    ++count;
    if (!set.name.empty()) set.ids.push_back(id);
    if (kind != ElementClass::kTet) {
      part.other_elements.insert(id);
      continue;
    }
    if (f.size() != 5) {
      return Error(line, absl::StrCat("element ", id, " of type ", type_name, " has ", f.size() - 1,
                                      " nodes, expected 4"));
    }
    Tet tet;
    for (int c = 0; c < 4; ++c) {
      int64_t node = 0;
      const auto it =
          ParseInt64(f[1 + c], node) ? part.node_index.find(node) : part.node_index.end();
      if (it == part.node_index.end()) {
        return Error(line, absl::StrCat("element ", id, ": node \"", f[1 + c].substr(0, 30),
                                        "\" is not defined by an earlier *NODE",
                                        part.name.empty() ? "" : " of part ", part.name));
      }
      tet[c] = it->second;
    }
    part.tet_index[id] = static_cast<uint32_t>(part.tets.size());
    part.tets.push_back(tet);
  }
  if (kind == ElementClass::kTet) {
    census_.AddTets(count);
  } else {
    census_.Add({absl::StrCat(type_name, " element"), absl::StrCat(type_name, " elements"),
                 kind == ElementClass::kOtherVolume ? CellFate::kUnsupported : CellFate::kSkip},
                count);
  }
  if (!set.name.empty()) {
    part.element_sets.push_back(std::move(set));
    part.element_sets_named[absl::AsciiStrToUpper(part.element_sets.back().name)] =
        &part.element_sets.back();
  }
  return absl::OkStatus();
}

absl::Status AbaqusParser::ReadSet(
    const Keyword& k, int64_t keyword_line,
    const std::function<const ElementSet*(const std::string&)>& named, ElementSet& set) {
  const auto name = k.params.find("ELSET");
  if (name == k.params.end() || name->second.empty()) {
    return Error(keyword_line, "*ELSET without ELSET=");
  }
  set.name = name->second;
  set.line = keyword_line;
  const bool generate = k.params.count("GENERATE") > 0;
  std::vector<absl::string_view> f;
  int64_t line = 0;
  while (NextRecord(f, line)) {
    std::vector<int64_t> numbers;
    for (absl::string_view field : f) {
      if (field.empty()) continue;
      int64_t n = 0;
      if (ParseInt64(field, n)) {
        numbers.push_back(n);
        continue;
      }
      const ElementSet* member = generate ? nullptr : named(absl::AsciiStrToUpper(field));
      if (member == nullptr) {
        return Error(line, absl::StrCat("*ELSET ", set.name, ": \"", field.substr(0, 30),
                                        "\" is neither an element id nor ",
                                        generate ? "allowed with GENERATE"
                                                 : "the name of an earlier element set"));
      }
      set.members.push_back(member);
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
  return absl::OkStatus();
}

absl::Status AbaqusParser::OpenPart(const Keyword& k, int64_t line) {
  const auto name = k.params.find("NAME");
  if (name == k.params.end() || name->second.empty()) return Error(line, "*PART without NAME=");
  if (!part_named_.emplace(absl::AsciiStrToUpper(name->second), parts_.size()).second) {
    return Error(line, absl::StrCat("part ", name->second, " is defined twice"));
  }
  current_ = parts_.size();
  parts_.emplace_back();
  parts_.back().name = name->second;
  parts_.back().line = line;
  scope_ = Scope::kPart;
  return absl::OkStatus();
}

absl::Status AbaqusParser::OpenInstance(const Keyword& k, int64_t line) {
  const auto name = k.params.find("NAME");
  const auto part = k.params.find("PART");
  if (name == k.params.end() || name->second.empty()) {
    return Error(line, "*INSTANCE without NAME=");
  }
  if (part == k.params.end() || part->second.empty()) {
    return Error(line, absl::StrCat("*INSTANCE ", name->second,
                                    " without PART= (instances that define their own "
                                    "nodes and elements are not read)"));
  }
  const auto found = part_named_.find(absl::AsciiStrToUpper(part->second));
  if (found == part_named_.end()) {
    return Error(line, absl::StrCat("*INSTANCE ", name->second, ": part ", part->second,
                                    " is not defined by an earlier *PART"));
  }
  if (!instance_named_.emplace(absl::AsciiStrToUpper(name->second), instances_.size()).second) {
    return Error(line, absl::StrCat("instance ", name->second, " is defined twice"));
  }
  Instance instance;
  instance.name = name->second;
  instance.line = line;
  instance.part = found->second;
  // Up to two data lines: the translation "x, y, z", then the rotation "ax, ay, az, bx, by, bz,
  // degrees".
  std::vector<absl::string_view> f;
  int64_t data_line = 0;
  for (int record = 0; NextRecord(f, data_line); ++record) {
    const size_t want = record == 0 ? 3 : 7;
    std::vector<double> numbers(f.size());
    bool finite = f.size() == want && record < 2;
    for (size_t i = 0; finite && i < f.size(); ++i) {
      finite = ParseDouble(f[i], numbers[i]) && std::isfinite(numbers[i]);
    }
    if (!finite) {
      return Error(data_line,
                   record >= 2
                       ? absl::StrCat("*INSTANCE ", instance.name, " has more than two data lines")
                       : absl::StrCat("*INSTANCE ", instance.name, ": expected ",
                                      record == 0 ? "a translation \"x, y, z\""
                                                  : "a rotation \"ax, ay, az, bx, by, "
                                                    "bz, degrees\"",
                                      " of finite numbers"));
    }
    if (record == 0) {
      instance.translation = {numbers[0], numbers[1], numbers[2]};
    } else {
      instance.rotated = true;
      instance.axis_a = {numbers[0], numbers[1], numbers[2]};
      instance.axis_b = {numbers[3], numbers[4], numbers[5]};
      instance.degrees = numbers[6];
      if (instance.axis_a == instance.axis_b) {
        return Error(data_line, absl::StrCat("*INSTANCE ", instance.name,
                                             ": the rotation axis's two points are the same"));
      }
    }
  }
  instances_.push_back(std::move(instance));
  scope_ = Scope::kInstance;
  return absl::OkStatus();
}

// The keywords that open and close parts, the assembly and instances; `handled` says whether k
// was one of them.
absl::Status AbaqusParser::Structure(const Keyword& k, int64_t line, bool& handled) {
  handled = true;
  const auto misplaced = [&](absl::string_view where) {
    return Error(line, absl::StrCat("*", k.name, " ", where));
  };
  if (k.name == "PART") {
    if (scope_ != Scope::kTop) return misplaced("inside another block (a missing *END?)");
    return OpenPart(k, line);
  }
  if (k.name == "END PART") {
    if (scope_ != Scope::kPart) return misplaced("without *PART");
    scope_ = Scope::kTop;
    current_ = 0;
    return absl::OkStatus();
  }
  if (k.name == "ASSEMBLY") {
    if (scope_ != Scope::kTop) return misplaced("inside another block (a missing *END?)");
    if (assembly_) return misplaced("a second time");
    assembly_ = true;
    scope_ = Scope::kAssembly;
    return absl::OkStatus();
  }
  if (k.name == "END ASSEMBLY") {
    if (scope_ != Scope::kAssembly) return misplaced("without *ASSEMBLY");
    scope_ = Scope::kTop;
    return absl::OkStatus();
  }
  if (k.name == "INSTANCE") {
    if (scope_ != Scope::kAssembly) return misplaced("outside *ASSEMBLY");
    return OpenInstance(k, line);
  }
  if (k.name == "END INSTANCE") {
    if (scope_ != Scope::kInstance) return misplaced("without *INSTANCE");
    scope_ = Scope::kAssembly;
    return absl::OkStatus();
  }
  handled = false;
  return absl::OkStatus();
}

absl::StatusOr<MeshFile> AbaqusParser::Assemble() {
  MeshFile file;
  file.skipped_cells = census_.SkippedCells();
  // The parts placed, in order: a flat file's own, or each instance's part.
  std::vector<size_t> placed;
  std::vector<uint32_t> tet_offset;
  const auto place = [&](const Part& part, const Instance* instance) -> absl::Status {
    if (file.mesh.points.size() + part.points.size() >= (size_t{1} << 32) - 1) {
      return Error(instance != nullptr ? instance->line : 0, "more than 2^32 - 1 nodes");
    }
    const uint32_t point_offset = static_cast<uint32_t>(file.mesh.points.size());
    tet_offset.push_back(static_cast<uint32_t>(file.mesh.tets.size()));
    for (Vec3 p : part.points) {
      if (instance != nullptr) {
        for (int a = 0; a < 3; ++a) p[a] += instance->translation[a];
        if (instance->rotated) {
          p = Rotate(p, instance->axis_a, instance->axis_b, instance->degrees);
        }
      }
      file.mesh.points.push_back(p);
    }
    for (Tet t : part.tets) {
      for (uint32_t& v : t) v += point_offset;
      file.mesh.tets.push_back(t);
    }
    return absl::OkStatus();
  };
  if (instances_.empty()) {
    for (size_t p = 1; p < parts_.size(); ++p) {
      if (!parts_[p].tets.empty()) {
        return Error(parts_[p].line, absl::StrCat("part ", parts_[p].name,
                                                  " has tetrahedra but no *INSTANCE in an "
                                                  "*ASSEMBLY places it"));
      }
    }
    placed.push_back(0);
    if (absl::Status s = place(parts_[0], nullptr); !s.ok()) return s;
  } else {
    if (!parts_[0].tets.empty()) {
      return Error(parts_[0].line, "elements outside *PART in a file whose assembly places parts");
    }
    // Instances copy their part without the file holding the copies: a few lines could ask for
    // billions of tets. Counted before anything is copied.
    uint64_t points = 0, tets = 0;
    for (const Instance& instance : instances_) {
      if (parts_[instance.part].tets.empty()) continue;
      points += parts_[instance.part].points.size();
      tets += parts_[instance.part].tets.size();
      if (points > kMaxPlaced || tets > kMaxPlaced) {
        return Error(instance.line,
                     absl::StrCat("the instances up to ", instance.name, " place more than ",
                                  kMaxPlaced, " ", points > kMaxPlaced ? "nodes" : "tetrahedra"));
      }
    }
    // Instances of parts without tets (rigid surfaces, shells) add nothing.
    for (const Instance& instance : instances_) {
      if (parts_[instance.part].tets.empty()) continue;
      placed.push_back(instance.part);
      if (absl::Status s = place(parts_[instance.part], &instance); !s.ok()) return s;
    }
  }
  if (absl::Status s = AssignLabels(file, placed, tet_offset); !s.ok()) return s;
  return file;
}

absl::Status AbaqusParser::AssignLabels(MeshFile& file, const std::vector<size_t>& placed,
                                        const std::vector<uint32_t>& tet_offset) {
  // The sets in the order they are taken: each placed part's (its *ELSET blocks, else the ELSET=
  // of its *ELEMENT blocks), then the assembly's. With several instances placed, a part's set
  // name is qualified by its instance's, as Abaqus/CAE shows it ("Part-1-1.Set-1").
  struct Candidate {
    const ElementSet* set;
    const Part* part;
    uint32_t offset;
    std::string name;
  };
  std::vector<Candidate> candidates;
  std::vector<const Instance*> placed_instances;
  std::vector<int64_t> placed_position(instances_.size(), -1);  // per instance, in `placed`
  for (size_t i = 0; i < instances_.size(); ++i) {
    if (parts_[instances_[i].part].tets.empty()) continue;
    placed_position[i] = static_cast<int64_t>(placed_instances.size());
    placed_instances.push_back(&instances_[i]);
  }
  for (size_t i = 0; i < placed.size(); ++i) {
    const Part& part = parts_[placed[i]];
    for (const ElementSet& set : part.sets.empty() ? part.element_sets : part.sets) {
      candidates.push_back({&set, &part, tet_offset[i],
                            placed_instances.size() > 1
                                ? absl::StrCat(placed_instances[i]->name, ".", set.name)
                                : set.name});
    }
  }
  for (const ElementSet& set : assembly_sets_) {
    const auto named = instance_named_.find(set.instance);
    const Instance* instance =
        named == instance_named_.end() ? nullptr : &instances_[named->second];
    if (instance == nullptr) {
      return Error(set.line, absl::StrCat("element set ", set.name, " names instance ",
                                          set.instance, ", which the assembly does not define"));
    }
    const int64_t at = placed_position[named->second];
    const uint32_t offset = at < 0 ? 0 : tet_offset[static_cast<size_t>(at)];
    candidates.push_back(
        {&set, &parts_[instance->part], offset,
         placed_instances.size() > 1 ? absl::StrCat(instance->name, ".", set.name) : set.name});
  }
  std::vector<int32_t> region(file.mesh.tets.size(), -1);  // index into `taken`, -1: none
  std::vector<const Candidate*> taken;
  // Every set is walked once per candidate that names it, directly or not: a file of many sets
  // that each name the one before would take quadratic time. The walk stops past this many ids
  // (real files walk a few times their element count; 2^28 is about ten seconds).
  int64_t walked = 0;
  for (const Candidate& candidate : candidates) {
    const ElementSet& set = *candidate.set;
    const Part& part = *candidate.part;
    std::vector<uint32_t> tets;
    bool overlaps = false;
    // The set being walked: `set` or one it names.
    const ElementSet* walking = &set;
    const auto take = [&](int64_t id) -> absl::Status {
      if (++walked > kMaxWalkedIds) {
        return Error(candidate.set->line,
                     absl::StrCat("the element sets name more than ", kMaxWalkedIds,
                                  " element ids in all, counting each set once for every set "
                                  "that names it; name fewer sets within sets"));
      }
      const auto it = part.tet_index.find(id);
      if (it == part.tet_index.end()) {
        if (part.other_elements.count(id) == 0) {
          return Error(
              walking->line,
              absl::StrCat(
                  "element set ", walking->name, " names element ", id, ", which ",
                  part.name.empty() ? std::string("the file") : absl::StrCat("part ", part.name),
                  " does not define"));
        }
        return absl::OkStatus();
      }
      const uint32_t t = candidate.offset + it->second;
      tets.push_back(t);
      if (region[t] >= 0) overlaps = true;
      return absl::OkStatus();
    };
    // Each set once, the named ones too, however often they are named.
    std::vector<const ElementSet*> to_walk = {&set};
    std::unordered_set<const ElementSet*> seen_sets = {&set};
    while (!to_walk.empty()) {
      walking = to_walk.back();
      to_walk.pop_back();
      for (int64_t id : walking->ids) {
        if (absl::Status s = take(id); !s.ok()) return s;
      }
      // A range longer than the part's element count names an element it does not define; the
      // walk below stops at the first such id, after at most that many steps.
      for (const IdRange& r : walking->ranges) {
        for (int64_t id = r.first; id <= r.last; id += r.step) {
          if (absl::Status s = take(id); !s.ok()) return s;
        }
      }
      for (const ElementSet* member : walking->members) {
        if (seen_sets.insert(member).second) to_walk.push_back(member);
      }
    }
    if (tets.empty() || overlaps) continue;
    for (uint32_t t : tets) region[t] = static_cast<int32_t>(taken.size());
    taken.push_back(&candidate);
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
      // Control characters (DEL too: the fuzzer found one that ValidateMeshFile then refused)
      // cannot be in a region name.
      if (c != '"' && static_cast<unsigned char>(c) >= 0x20 && c != 0x7f) name += c;
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
  if (absl::Status s = AddLines(text_, 0, 0); !s.ok()) return s;
  while (at_ < lines_.size()) {
    const absl::string_view raw = absl::StripAsciiWhitespace(lines_[at_]);
    const int64_t line = static_cast<int64_t>(at_);
    ++at_;
    if (raw.empty() || IsComment(raw)) continue;
    if (raw[0] != '*') {
      return Error(line, "data line outside any keyword block");
    }
    Keyword k = ParseKeyword(raw);
    // "*End Part" and "*EndPart" alike.
    if (absl::StartsWith(k.name, "END") && k.name.size() > 3 && k.name[3] != ' ') {
      k.name.insert(3, " ");
    }
    if (k.name == "INCLUDE") {
      const auto [source, number] = where_[static_cast<size_t>(line)];
      return FileUnsupported(sources_[source],
                             absl::StrCat("line ", number + 1,
                                          ": *INCLUDE is not followed here; put the included "
                                          "file's lines in its place"));
    }
    bool handled = false;
    if (absl::Status s = Structure(k, line, handled); !s.ok() || handled) {
      if (!s.ok()) return s;
      continue;
    }
    absl::Status s;
    const bool in_part = scope_ == Scope::kTop || scope_ == Scope::kPart;
    if (k.name == "NODE" && in_part) {
      s = ReadNodes(parts_[current_]);
    } else if (k.name == "ELEMENT" && in_part) {
      s = ReadElements(parts_[current_], k, line);
    } else if (k.name == "ELSET" && in_part) {
      Part& part = parts_[current_];
      ElementSet set;
      s = ReadSet(
          k, line,
          [&part](const std::string& name) -> const ElementSet* {
            for (const auto* named : {&part.sets_named, &part.element_sets_named}) {
              if (const auto it = named->find(name); it != named->end()) return it->second;
            }
            return nullptr;
          },
          set);
      part.sets.push_back(std::move(set));
      part.sets_named[absl::AsciiStrToUpper(part.sets.back().name)] = &part.sets.back();
    } else if (k.name == "ELSET" && k.params.count("INSTANCE") > 0) {
      // An assembly's set of one instance's elements, numbered as its part numbers them.
      ElementSet set;
      const std::string instance = absl::AsciiStrToUpper(k.params.at("INSTANCE"));
      s = ReadSet(
          k, line,
          [&](const std::string& name) -> const ElementSet* {
            const auto it = assembly_sets_named_.find(absl::StrCat(instance, "\n", name));
            return it == assembly_sets_named_.end() ? nullptr : it->second;
          },
          set);
      set.instance = instance;
      assembly_sets_.push_back(std::move(set));
      assembly_sets_named_[absl::StrCat(instance, "\n",
                                        absl::AsciiStrToUpper(assembly_sets_.back().name))] =
          &assembly_sets_.back();
    } else if ((k.name == "NODE" || k.name == "ELEMENT") && scope_ == Scope::kInstance) {
      return Error(line, absl::StrCat("*", k.name,
                                      " inside *INSTANCE: instances that define "
                                      "their own nodes and elements are not read"));
    } else {
      // Anything else (HEADING's title, NSET, MATERIAL, STEP, an assembly's reference nodes and
      // connector elements, ...): its data lines are skipped.
      SkipData();
    }
    if (!s.ok()) return s;
  }
  if (scope_ != Scope::kTop) {
    return Error(static_cast<int64_t>(lines_.size()) - 1,
                 scope_ == Scope::kPart ? "the file ends inside *PART (no *END PART)"
                 : scope_ == Scope::kAssembly
                     ? "the file ends inside *ASSEMBLY (no *END ASSEMBLY)"
                     : "the file ends inside *INSTANCE (no *END INSTANCE)");
  }
  if (absl::Status s = census_.Check(sources_[0]); !s.ok()) return s;
  return Assemble();
}

}  // namespace

absl::StatusOr<MeshFile> ParseAbaqus(absl::string_view text, absl::string_view path,
                                     const AbaqusIncludeReader& include) {
  return AbaqusParser(text, path, include).Parse();
}

}  // namespace tetrefine::io
