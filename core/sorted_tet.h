#pragma once

#include <algorithm>
#include <array>

#include "core/mesh.h"

namespace tetrefine {

// A tet's vertex ids in increasing order, and whether putting them in that order was an odd
// permutation of the tet's own order. For a positively oriented tet (a, b, c, d) the parity says
// on which side of each sorted face the opposite vertex lies, with no determinant to compute.
struct SortedTet {
  std::array<uint32_t, 4> v;
  bool odd;
  std::array<uint8_t, 4> local;  // local[i]: the tet corner (0..3) that v[i] came from
};

inline SortedTet SortTet(const Tet& t) {
  SortedTet s{t, false, {0, 1, 2, 3}};
  // A 5-comparator sorting network; each swap flips the parity.
  auto cmp = [&](int i, int j) {
    if (s.v[j] < s.v[i]) {
      std::swap(s.v[i], s.v[j]);
      std::swap(s.local[i], s.local[j]);
      s.odd = !s.odd;
    }
  };
  cmp(0, 1);
  cmp(2, 3);
  cmp(0, 2);
  cmp(1, 3);
  cmp(1, 2);
  return s;
}

}  // namespace tetrefine
