#pragma once

#include <array>
#include <cstdint>
#include <string_view>

namespace tetrefine {

// The paper's 11 subdivision configurations (Figure 3, Table 1), by number of split edges and
// their arrangement. The enumerator order is the order of the paper's tables.
enum class Configuration : uint8_t {
  k0,   // no split edge: tet kept
  k1,   // one edge: 2 tets
  k2a,  // two edges on one face: 3 tets
  k2b,  // two opposite edges: 4 tets
  k3a,  // three edges of one face: 4 tets
  k3b,  // three edges through one vertex: 4 tets, 9 with a Steiner point
  k3c,  // a path of three edges (two opposite): 5 tets
  k4a,  // a face's three edges plus one more: 6 tets
  k4b,  // all but two opposite edges: 6 tets, 11 with a Steiner point
  k5,   // all but one edge: 7 tets
  k6,   // all six edges: 8 tets
};
inline constexpr int kNumConfigurations = 11;

// "0", "1", "2a", ... as in the paper.
std::string_view ConfigurationName(Configuration c);

// Tets produced by configuration c without / with a Steiner point (Table 1).
int ConfigurationTetCount(Configuration c, bool steiner);

using ConfigurationCounts = std::array<int64_t, kNumConfigurations>;

}  // namespace tetrefine
