#include "core/mesh_validation.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <memory>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "core/parallel.h"
#include "core/sorted_tet.h"

namespace tetrefine {
namespace {

std::string Point(const Vec3& p) { return absl::StrFormat("(%g, %g, %g)", p[0], p[1], p[2]); }

double LongestEdgeSquared(const Mesh& m, const Tet& t) {
  double l = 0.0;
  for (int i = 0; i < 4; ++i) {
    for (int j = i + 1; j < 4; ++j) {
      const Vec3& a = m.points[t[i]];
      const Vec3& b = m.points[t[j]];
      const double dx = a[0] - b[0], dy = a[1] - b[1], dz = a[2] - b[2];
      l = std::max(l, dx * dx + dy * dy + dz * dz);
    }
  }
  return l;
}

enum class TetIssue { kNone, kRange, kRepeat, kDegenerate, kInverted };

// A tet is degenerate when |6V| <= 1e-12 L^3, L its longest edge: scale-free, and far below any
// tet a mesher or this refiner makes.
bool IsDegenerate(double v6, double l2) { return std::abs(v6) <= 1e-12 * l2 * std::sqrt(l2); }

TetIssue InspectTet(const Mesh& m, const Tet& tet, int64_t num_points, bool reject_inverted) {
  for (int k = 0; k < 4; ++k) {
    if (tet[k] >= num_points) return TetIssue::kRange;
    for (int j = 0; j < k; ++j) {
      if (tet[j] == tet[k]) return TetIssue::kRepeat;
    }
  }
  const double v6 =
      SignedVolume6(m.points[tet[0]], m.points[tet[1]], m.points[tet[2]], m.points[tet[3]]);
  if (IsDegenerate(v6, LongestEdgeSquared(m, tet))) return TetIssue::kDegenerate;
  if (v6 < 0.0 && reject_inverted) return TetIssue::kInverted;
  return TetIssue::kNone;
}

absl::Status DescribeTet(const Mesh& m, int64_t t, int64_t num_points) {
  const Tet& tet = m.tets[t];
  for (int k = 0; k < 4; ++k) {
    if (tet[k] >= num_points) {
      return absl::InvalidArgumentError(absl::StrCat("mesh.tets[", t, "][", k, "] = ", tet[k],
                                                     " is out of range (", num_points,
                                                     " vertices)"));
    }
    for (int j = 0; j < k; ++j) {
      if (tet[j] == tet[k]) {
        return absl::InvalidArgumentError(
            absl::StrCat("mesh.tets[", t, "] repeats vertex ", tet[k], ": the tet is degenerate"));
      }
    }
  }
  const double v6 =
      SignedVolume6(m.points[tet[0]], m.points[tet[1]], m.points[tet[2]], m.points[tet[3]]);
  const double l2 = LongestEdgeSquared(m, tet);
  if (IsDegenerate(v6, l2)) {
    return absl::InvalidArgumentError(absl::StrCat("mesh.tets[", t, "] is degenerate: volume ",
                                                   v6 / 6.0, " for longest edge ", std::sqrt(l2)));
  }
  return absl::InvalidArgumentError(
      absl::StrCat("mesh.tets[", t, "] is inverted (negative volume ", v6 / 6.0,
                   "); tets must be positively oriented, or ask to normalize orientation"));
}

struct FaceUse {
  uint32_t b, c;  // the face's two larger vertices (the smallest is the bucket)
  uint32_t tet;
  int8_t side;  // +1 or -1: which side of the face (in sorted vertex order) the tet lies on
};

}  // namespace

absl::Status CheckFaces(const std::vector<Vec3>& points, const std::vector<Tet>& tets) {
  const int64_t num_points = static_cast<int64_t>(points.size());
  const int64_t num_tets = static_cast<int64_t>(tets.size());
  // Bucket each face by its smallest vertex. With a tet's vertices sorted (v0 < v1 < v2 < v3),
  // the faces without v3, v2, v1 start at v0 and the face without v0 starts at v1.
  std::unique_ptr<std::atomic<uint32_t>[]> count(new std::atomic<uint32_t>[num_points]);
  for (int64_t v = 0; v < num_points; ++v) count[v].store(0, std::memory_order_relaxed);
  ForEachBlock(num_tets, [&](int64_t, int64_t begin, int64_t end) {
    for (int64_t t = begin; t < end; ++t) {
      const SortedTet s = SortTet(tets[t]);
      count[s.v[0]].fetch_add(3, std::memory_order_relaxed);
      count[s.v[1]].fetch_add(1, std::memory_order_relaxed);
    }
  });
  std::vector<uint64_t> start(num_points + 1, 0);
  for (int64_t v = 0; v < num_points; ++v) {
    start[v + 1] = start[v] + count[v].load(std::memory_order_relaxed);
    count[v].store(0, std::memory_order_relaxed);
  }
  std::vector<FaceUse> uses(start[num_points]);
  ForEachBlock(num_tets, [&](int64_t, int64_t begin, int64_t end) {
    for (int64_t t = begin; t < end; ++t) {
      const SortedTet s = SortTet(tets[t]);
      // The tet is positively oriented, so (v0, v1, v2, v3) is positive iff sorting was even;
      // moving the left-out vertex v_k to the end takes 3 - k transpositions.
      const int8_t base = s.odd ? -1 : 1;
      const auto tet = static_cast<uint32_t>(t);
      uint64_t slot = start[s.v[0]] + count[s.v[0]].fetch_add(3, std::memory_order_relaxed);
      uses[slot++] = {s.v[1], s.v[2], tet, base};                        // without v3
      uses[slot++] = {s.v[1], s.v[3], tet, static_cast<int8_t>(-base)};  // without v2
      uses[slot] = {s.v[2], s.v[3], tet, base};                          // without v1
      slot = start[s.v[1]] + count[s.v[1]].fetch_add(1, std::memory_order_relaxed);
      uses[slot] = {s.v[2], s.v[3], tet, static_cast<int8_t>(-base)};  // without v0
    }
  });
  // The first bad vertex bucket, so the message does not depend on thread timing.
  std::atomic<int64_t> first_bad{num_points};
  ForEachBlock(num_points, [&](int64_t, int64_t begin, int64_t end) {
    for (int64_t v = begin; v < end && v < first_bad.load(); ++v) {
      auto* b = uses.data() + start[v];
      auto* e = uses.data() + start[v + 1];
      SortSmall(b, e, [](const FaceUse& x, const FaceUse& y) {
        return std::tie(x.b, x.c, x.tet) < std::tie(y.b, y.c, y.tet);
      });
      for (auto* p = b; p < e;) {
        auto* q = p;
        while (q < e && q->b == p->b && q->c == p->c) ++q;
        if (q - p > 2 || (q - p == 2 && p[0].side == p[1].side)) {
          int64_t cur = first_bad.load();
          while (v < cur && !first_bad.compare_exchange_weak(cur, v)) {
          }
          break;
        }
        p = q;
      }
    }
  });
  const int64_t v = first_bad.load();
  if (v == num_points) return absl::OkStatus();
  auto* b = uses.data() + start[v];
  auto* e = uses.data() + start[v + 1];
  for (auto* p = b; p < e;) {
    auto* q = p;
    while (q < e && q->b == p->b && q->c == p->c) ++q;
    const std::string face = absl::StrCat("(", v, ", ", p->b, ", ", p->c, ")");
    if (q - p > 2) {
      return absl::InvalidArgumentError(absl::StrCat(
          "mesh.tets: face ", face, " is shared by ", q - p, " tets (mesh.tets[", p[0].tet, "], [",
          p[1].tet, "], [", p[2].tet, "]): a face may belong to at most two"));
    }
    if (q - p == 2 && p[0].side == p[1].side) {
      return absl::InvalidArgumentError(absl::StrCat("mesh.tets[", p[0].tet, "] and mesh.tets[",
                                                     p[1].tet,
                                                     "] overlap: both lie on the same "
                                                     "side of their shared face ",
                                                     face));
    }
    p = q;
  }
  return absl::InternalError("face check disagreed with itself");
}

absl::Status ValidateMesh(const Mesh& mesh, const Volume& volume, OutsidePolicy outside,
                          OrientationPolicy orientation, std::vector<Tet>* tets,
                          int64_t* reoriented) {
  const int64_t num_points = static_cast<int64_t>(mesh.points.size());
  if (mesh.tets.empty()) return absl::InvalidArgumentError("mesh.tets is empty");
  if (num_points > std::numeric_limits<uint32_t>::max() / 2) {
    return absl::InvalidArgumentError(
        absl::StrCat("mesh.points has ", num_points, " vertices; at most 2^31 are supported"));
  }
  const int64_t bad_point = FirstIndexWhere(num_points, [&](int64_t i) {
    const Vec3& p = mesh.points[i];
    return !std::isfinite(p[0]) || !std::isfinite(p[1]) || !std::isfinite(p[2]);
  });
  if (bad_point < num_points) {
    return absl::InvalidArgumentError(absl::StrCat(
        "mesh.points[", bad_point, "] = ", Point(mesh.points[bad_point]), " is not finite"));
  }
  const int64_t num_tets = static_cast<int64_t>(mesh.tets.size());
  const bool reject_inverted = orientation == OrientationPolicy::kReject;
  const int64_t bad_tet = FirstIndexWhere(num_tets, [&](int64_t t) {
    return InspectTet(mesh, mesh.tets[t], num_points, reject_inverted) != TetIssue::kNone;
  });
  if (bad_tet < num_tets) return DescribeTet(mesh, bad_tet, num_points);
  *tets = mesh.tets;
  const int64_t blocks = BlockCount(num_tets);
  std::vector<int64_t> flipped(blocks, 0);
  if (!reject_inverted) {
    ForEachBlock(num_tets, [&](int64_t b, int64_t begin, int64_t end) {
      for (int64_t t = begin; t < end; ++t) {
        Tet& tet = (*tets)[t];
        if (SignedVolume6(mesh.points[tet[0]], mesh.points[tet[1]], mesh.points[tet[2]],
                          mesh.points[tet[3]]) < 0.0) {
          std::swap(tet[2], tet[3]);
          ++flipped[b];
        }
      }
    });
  }
  *reoriented = 0;
  for (int64_t f : flipped) *reoriented += f;
  if (outside == OutsidePolicy::kReject) {
    const int64_t out = FirstIndexWhere(num_points, [&](int64_t i) {
      return !volume.Contains(volume.ContinuousIndex(mesh.points[i]));
    });
    if (out < num_points) {
      const GridGeometry& g = volume.grid();
      std::string box;
      for (int a = 0; a < 3; ++a) {
        absl::StrAppend(&box, a ? " x " : "", "[",
                        g.origin[a] + static_cast<double>(volume.lo()[a]) * g.spacing[a], ", ",
                        g.origin[a] + static_cast<double>(volume.hi()[a] - 1) * g.spacing[a], "]");
      }
      return absl::InvalidArgumentError(
          absl::StrCat("mesh.points[", out, "] = ", Point(mesh.points[out]),
                       " lies outside the volume's sampled box ", box));
    }
  }
  return CheckFaces(mesh.points, *tets);
}

}  // namespace tetrefine
