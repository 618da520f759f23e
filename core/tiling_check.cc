#include "core/tiling_check.h"

#include <algorithm>
#include <map>

#include "absl/strings/str_cat.h"
#include "core/mesh.h"

namespace tetrefine {
namespace {

using Face = std::array<int, 3>;

Face Sorted(Face f) {
  std::sort(f.begin(), f.end());
  return f;
}

bool Fail(std::string* why, std::string message) {
  if (why != nullptr) *why = std::move(message);
  return false;
}

}  // namespace

bool IsTiling(std::span<const std::array<int, 4>> tets,
              std::span<const std::array<int, 3>> boundary, std::span<const Vec3> points,
              std::string* why) {
  struct Use {
    int count = 0;
    double side[2] = {0.0, 0.0};  // signed volume of (face, opposite corner) per use
  };
  std::map<Face, Use> faces;
  for (size_t t = 0; t < tets.size(); ++t) {
    const auto& q = tets[t];
    if (SignedVolume6(points[q[0]], points[q[1]], points[q[2]], points[q[3]]) <= 0.0) {
      return Fail(why, absl::StrCat("tet ", t, " (", q[0], " ", q[1], " ", q[2], " ", q[3],
                                    ") has no positive volume"));
    }
    for (int skip = 0; skip < 4; ++skip) {
      Face f;
      int k = 0;
      for (int i = 0; i < 4; ++i) {
        if (i != skip) f[k++] = q[i];
      }
      const Face s = Sorted(f);
      Use& use = faces[s];
      if (use.count >= 2) {
        return Fail(why, absl::StrCat("face (", s[0], " ", s[1], " ", s[2],
                                      ") is shared by more than two tets"));
      }
      use.side[use.count++] =
          SignedVolume6(points[s[0]], points[s[1]], points[s[2]], points[q[skip]]);
    }
  }
  std::map<Face, int> on_boundary;
  for (const auto& b : boundary) ++on_boundary[Sorted(b)];
  for (const auto& [f, n] : on_boundary) {
    if (n != 1) return Fail(why, "a boundary triangle is listed twice");
    auto it = faces.find(f);
    if (it == faces.end() || it->second.count != 1) {
      return Fail(why, absl::StrCat("boundary triangle (", f[0], " ", f[1], " ", f[2],
                                    ") is not the face of exactly one tet"));
    }
  }
  for (const auto& [f, use] : faces) {
    if (on_boundary.count(f) != 0) continue;
    if (use.count != 2) {
      return Fail(why, absl::StrCat("face (", f[0], " ", f[1], " ", f[2],
                                    ") is on no boundary triangle and belongs to one tet"));
    }
    if ((use.side[0] > 0.0) == (use.side[1] > 0.0)) {
      return Fail(why,
                  absl::StrCat("the two tets at face (", f[0], " ", f[1], " ", f[2], ") overlap"));
    }
  }
  return true;
}

}  // namespace tetrefine
