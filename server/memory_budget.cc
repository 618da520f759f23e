#include "server/memory_budget.h"

#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <string_view>
#include <vector>

#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/strings/strip.h"
#include "core/subdivision_table.h"

namespace tetrefine::server {
namespace {

// v1 reports "no limit" as the largest page-aligned int64; anything this large is none.
constexpr int64_t kNoLimitAbove = int64_t{1} << 60;

std::optional<int64_t> ReadLimitFile(const std::string& path) {
  std::ifstream in(path);
  std::string text;
  if (!in || !std::getline(in, text)) return std::nullopt;
  int64_t value = 0;
  if (!absl::SimpleAtoi(absl::StripAsciiWhitespace(text), &value)) return std::nullopt;  // "max"
  if (value <= 0 || value >= kNoLimitAbove) return std::nullopt;
  return value;
}

// The cgroup paths of this process: "0::/a/b" (v2) and "4:memory:/a/b" (v1).
void OwnCgroupPaths(const std::string& root, std::string* v2, std::string* v1) {
  std::ifstream in(root + "proc/self/cgroup");
  for (std::string line; std::getline(in, line);) {
    const size_t first = line.find(':');
    const size_t second = first == std::string::npos ? first : line.find(':', first + 1);
    if (second == std::string::npos) continue;
    const std::string controllers = line.substr(first + 1, second - first - 1);
    const std::string path = line.substr(second + 1);
    if (controllers.empty()) *v2 = path;
    std::stringstream list(controllers);
    for (std::string c; std::getline(list, c, ',');) {
      if (c == "memory") *v1 = path;
    }
  }
}

}  // namespace

std::optional<int64_t> CgroupMemoryLimit(const std::string& root_in) {
  const std::string root = root_in.empty() || root_in.back() == '/' ? root_in : root_in + "/";
  std::string v2_path, v1_path;
  OwnCgroupPaths(root, &v2_path, &v1_path);
  std::vector<std::string> files = {root + "sys/fs/cgroup/memory.max",
                                    root + "sys/fs/cgroup/memory/memory.limit_in_bytes"};
  if (!v2_path.empty() && v2_path != "/") {
    files.push_back(root + "sys/fs/cgroup" + v2_path + "/memory.max");
  }
  if (!v1_path.empty() && v1_path != "/") {
    files.push_back(root + "sys/fs/cgroup/memory" + v1_path + "/memory.limit_in_bytes");
  }
  std::optional<int64_t> limit;
  for (const std::string& file : files) {
    if (std::optional<int64_t> l = ReadLimitFile(file)) limit = std::min(limit.value_or(*l), *l);
  }
  return limit;
}

int64_t PhysicalMemoryBytes() {
  return static_cast<int64_t>(sysconf(_SC_PHYS_PAGES)) *
         static_cast<int64_t>(sysconf(_SC_PAGESIZE));
}

namespace {

// A "kB" field of /proc/self/status, in bytes; nullopt when it cannot be read.
std::optional<int64_t> OwnStatusBytes(absl::string_view field) {
  std::ifstream in("/proc/self/status");
  for (std::string line; std::getline(in, line);) {
    absl::string_view rest = line;
    if (!absl::ConsumePrefix(&rest, field) || !absl::ConsumePrefix(&rest, ":")) continue;
    rest = absl::StripAsciiWhitespace(rest);
    if (!absl::ConsumeSuffix(&rest, "kB")) return std::nullopt;
    int64_t kb = 0;
    if (!absl::SimpleAtoi(absl::StripAsciiWhitespace(rest), &kb)) return std::nullopt;
    return kb * 1024;
  }
  return std::nullopt;
}

}  // namespace

std::optional<int64_t> AddressSpaceLeft() {
  std::optional<int64_t> left;
  for (const auto& [resource, field] : {std::pair{RLIMIT_AS, "VmSize"}, {RLIMIT_DATA, "VmData"}}) {
    rlimit limit{};
    if (getrlimit(resource, &limit) != 0 || limit.rlim_cur == RLIM_INFINITY) continue;
    const int64_t cap =
        static_cast<int64_t>(std::min<rlim_t>(limit.rlim_cur, static_cast<rlim_t>(kNoLimitAbove)));
    if (cap >= kNoLimitAbove) continue;
    const int64_t here = std::max<int64_t>(0, cap - OwnStatusBytes(field).value_or(0));
    left = std::min(left.value_or(here), here);
  }
  return left;
}

int64_t BudgetForLimit(int64_t limit_bytes) {
  const int64_t reserve = std::max<int64_t>(int64_t{256} << 20, limit_bytes / 10);
  return std::max<int64_t>(0, limit_bytes - reserve);
}

int64_t MaxChildrenPerTet() {
  static const int64_t children = [] {
    int64_t most = 1;
    for (const SubdivisionEntry& entry : SubdivisionTable()) {
      if (entry.valid) most = std::max<int64_t>(most, entry.tet_count);
    }
    return most;
  }();
  return children;
}

int64_t WorstCaseOutputTets(int64_t input_tets, int max_iterations, int64_t max_tets) {
  int64_t tets = std::max<int64_t>(input_tets, 1);
  for (int i = 0; i < max_iterations && tets < max_tets; ++i) {
    tets = tets > max_tets / MaxChildrenPerTet() ? max_tets : tets * MaxChildrenPerTet();
  }
  return std::min(tets, max_tets);
}

std::string HumanBytes(int64_t bytes) {
  constexpr const char* kUnits[] = {"B", "KiB", "MiB", "GiB", "TiB"};
  double value = static_cast<double>(bytes);
  int unit = 0;
  while (value >= 1024.0 && unit < 4) {
    value /= 1024.0;
    ++unit;
  }
  return unit == 0 ? absl::StrCat(bytes, " B") : absl::StrFormat("%.1f %s", value, kUnits[unit]);
}

}  // namespace tetrefine::server
