#include "core/tiling_check.h"

#include <algorithm>
#include <vector>

#include "absl/strings/str_cat.h"
#include "core/mesh.h"

namespace tetrefine {
namespace {

using Face = std::array<int, 3>;

Face Sorted(Face f) {
  std::sort(f.begin(), f.end());
  return f;
}

// `message` is called only when the caller wants the reason: the subdivision table's search
// rejects hundreds of candidate tilings per prism and reads none of the reasons.
template <typename Message>
bool Fail(std::string* why, Message message) {
  if (why != nullptr) *why = message();
  return false;
}

}  // namespace

bool IsTiling(std::span<const std::array<int, 4>> tets,
              std::span<const std::array<int, 3>> boundary, std::span<const Vec3> points,
              std::string* why) {
  // Sorted vectors rather than maps: the subdivision table is built at every process start by
  // trying up to 455 candidate tilings per prism, and a map allocates a node per face. Under
  // AddressSanitizer that made the build 0.53 s of every CLI run and server start (2026-11-24).
  struct FaceUse {
    Face face;    // sorted corners
    double side;  // signed volume of (face, the tet's opposite corner)
  };
  std::vector<FaceUse> uses;
  uses.reserve(4 * tets.size());
  for (size_t t = 0; t < tets.size(); ++t) {
    const auto& q = tets[t];
    if (SignedVolume6(points[q[0]], points[q[1]], points[q[2]], points[q[3]]) <= 0.0) {
      return Fail(why, [&] {
        return absl::StrCat("tet ", t, " (", q[0], " ", q[1], " ", q[2], " ", q[3],
                            ") has no positive volume");
      });
    }
    for (int skip = 0; skip < 4; ++skip) {
      Face f;
      int k = 0;
      for (int i = 0; i < 4; ++i) {
        if (i != skip) f[k++] = q[i];
      }
      const Face s = Sorted(f);
      uses.push_back({s, SignedVolume6(points[s[0]], points[s[1]], points[s[2]], points[q[skip]])});
    }
  }
  std::stable_sort(uses.begin(), uses.end(),
                   [](const FaceUse& a, const FaceUse& b) { return a.face < b.face; });
  std::vector<Face> on_boundary;
  on_boundary.reserve(boundary.size());
  for (const auto& b : boundary) on_boundary.push_back(Sorted(b));
  std::sort(on_boundary.begin(), on_boundary.end());
  if (std::adjacent_find(on_boundary.begin(), on_boundary.end()) != on_boundary.end()) {
    return Fail(why, [] { return std::string("a boundary triangle is listed twice"); });
  }
  // Each run of equal faces in `uses` is one face and the tets that have it.
  for (size_t begin = 0; begin < uses.size();) {
    size_t end = begin + 1;
    while (end < uses.size() && uses[end].face == uses[begin].face) ++end;
    const Face& f = uses[begin].face;
    const size_t count = end - begin;
    if (count > 2) {
      return Fail(why, [&] {
        return absl::StrCat("face (", f[0], " ", f[1], " ", f[2],
                            ") is shared by more than two tets");
      });
    }
    if (std::binary_search(on_boundary.begin(), on_boundary.end(), f)) {
      if (count != 1) {
        return Fail(why, [&] {
          return absl::StrCat("boundary triangle (", f[0], " ", f[1], " ", f[2],
                              ") is not the face of exactly one tet");
        });
      }
    } else if (count != 2) {
      return Fail(why, [&] {
        return absl::StrCat("face (", f[0], " ", f[1], " ", f[2],
                            ") is on no boundary triangle and belongs to one tet");
      });
    } else if ((uses[begin].side > 0.0) == (uses[begin + 1].side > 0.0)) {
      return Fail(why, [&] {
        return absl::StrCat("the two tets at face (", f[0], " ", f[1], " ", f[2], ") overlap");
      });
    }
    begin = end;
  }
  // A boundary triangle that is no tet's face at all.
  for (const Face& f : on_boundary) {
    const auto it = std::lower_bound(uses.begin(), uses.end(), f,
                                     [](const FaceUse& u, const Face& g) { return u.face < g; });
    if (it == uses.end() || it->face != f) {
      return Fail(why, [&] {
        return absl::StrCat("boundary triangle (", f[0], " ", f[1], " ", f[2],
                            ") is not the face of exactly one tet");
      });
    }
  }
  return true;
}

}  // namespace tetrefine
