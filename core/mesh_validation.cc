#include "core/mesh_validation.h"

#include <algorithm>
#include <atomic>
#include <bit>
#include <cmath>
#include <limits>
#include <memory>
#include <optional>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "core/counting_sort.h"
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

// One tet's use of a face, in the bucket of the face's smallest vertex: the two larger vertices
// b < c and the side of the face (in sorted vertex order) the tet lies on, packed as
// (b << 32) | (c << 1) | side. Eight bytes, not sixteen with the tet's index: the face check is
// bound by memory traffic, and only an error message needs the tets, found again then.
using FaceUse = uint64_t;

FaceUse PackFaceUse(uint32_t b, uint32_t c, bool positive) {
  return (static_cast<uint64_t>(b) << 32) | (static_cast<uint64_t>(c) << 1) | (positive ? 1 : 0);
}
uint64_t FaceOf(FaceUse u) { return u >> 1; }
int FaceSide(FaceUse u) { return static_cast<int>(u & 1); }

// One face of a bucket in the open-addressing table of BucketIsManifold.
struct FaceSlot {
  uint64_t face;  // FaceOf(use), or kNoFace
  uint8_t side;   // the side of the first tet seen on it
  uint8_t uses;   // tets seen on it
};
constexpr uint64_t kNoFace = ~uint64_t{0};  // FaceOf() is below 2^63

// True when every face in [b, e) (the faces whose smallest vertex is one bucket's) is used by
// at most two tets, and by two only from opposite sides. A hash table instead of a sort: a
// check that passes needs no order.
// When `boundary` is not null, the bucket's faces of one tet go there, as (v, b, c) with v the
// bucket's vertex.
bool BucketIsManifold(uint32_t v, const FaceUse* b, const FaceUse* e, std::vector<FaceSlot>& table,
                      std::vector<BoundaryFace>* boundary) {
  const size_t slots = std::bit_ceil(static_cast<size_t>(2 * (e - b) + 2));
  table.assign(slots, FaceSlot{kNoFace, 0, 0});
  const int shift = 64 - std::countr_zero(slots);
  auto find = [&](uint64_t face) -> FaceSlot& {
    // Fibonacci hashing; linear probing in a table at most half full.
    size_t h = (face * 0x9E3779B97F4A7C15ull) >> shift;
    while (table[h].face != kNoFace && table[h].face != face) h = (h + 1) & (slots - 1);
    return table[h];
  };
  int64_t singles = 0;  // faces seen once so far
  for (const FaceUse* p = b; p < e; ++p) {
    const uint64_t face = FaceOf(*p);
    const auto side = static_cast<uint8_t>(FaceSide(*p));
    FaceSlot& slot = find(face);
    if (slot.face == kNoFace) {
      slot = {face, side, 1};
      ++singles;
    } else if (slot.uses == 1 && slot.side != side) {
      slot.uses = 2;
      --singles;
    } else {
      return false;
    }
  }
  // Most buckets of a volume mesh hold no boundary face; the others are probed again in the
  // order of their uses, which depends only on the tets.
  if (boundary != nullptr && singles > 0) {
    for (const FaceUse* p = b; p < e; ++p) {
      const uint64_t face = FaceOf(*p);
      if (find(face).uses != 1) continue;
      boundary->push_back(
          {v, static_cast<uint32_t>(face >> 31), static_cast<uint32_t>(face & 0x7fffffffu)});
    }
  }
  return true;
}

// The tets, in index order, that have all of face's vertices (at most `limit` of them).
std::vector<int64_t> TetsOnFace(const std::vector<Tet>& tets, const std::array<uint32_t, 3>& face,
                                size_t limit) {
  std::vector<int64_t> found;
  for (int64_t t = 0; t < static_cast<int64_t>(tets.size()) && found.size() < limit; ++t) {
    const Tet& tet = tets[t];
    const bool has_all = std::all_of(face.begin(), face.end(), [&](uint32_t v) {
      return std::find(tet.begin(), tet.end(), v) != tet.end();
    });
    if (has_all) found.push_back(t);
  }
  return found;
}

}  // namespace

absl::Status CheckFaces(const std::vector<Vec3>& points, const std::vector<Tet>& tets,
                        std::vector<BoundaryFace>* boundary) {
  const int64_t num_points = static_cast<int64_t>(points.size());
  const int64_t num_tets = static_cast<int64_t>(tets.size());
  // Bucket each face by its smallest vertex (a counting sort). With a tet's vertices sorted
  // (v0 < v1 < v2 < v3), the faces without v3, v2, v1 start at v0 and the face without v0
  // starts at v1.
  std::unique_ptr<FaceUse[]> uses;
  const BucketLayout layout = CountingSort(
      num_tets, num_points,
      [&](int64_t t, auto add) {
        const SortedTet s = SortTet(tets[t]);
        add(s.v[0], 3);
        add(s.v[1], 1);
      },
      [&](uint64_t total) { uses.reset(new FaceUse[total]); },
      [&](int64_t t, auto slot) {
        const SortedTet s = SortTet(tets[t]);
        // The tet is positively oriented, so (v0, v1, v2, v3) is positive iff sorting was even;
        // moving the left-out vertex v_k to the end takes 3 - k transpositions.
        const bool even = !s.odd;
        FaceUse* out = uses.get() + slot(s.v[0], 3);
        out[0] = PackFaceUse(s.v[1], s.v[2], even);                  // without v3
        out[1] = PackFaceUse(s.v[1], s.v[3], !even);                 // without v2
        out[2] = PackFaceUse(s.v[2], s.v[3], even);                  // without v1
        uses[slot(s.v[1], 1)] = PackFaceUse(s.v[2], s.v[3], !even);  // without v0
      });
  const auto& start = layout.start;
  // The first bad vertex bucket, so the message does not depend on thread timing.
  std::atomic<int64_t> first_bad{num_points};
  // Per block, so the list's order does not depend on the thread count.
  std::vector<std::vector<BoundaryFace>> found(boundary != nullptr ? BlockCount(num_points) : 0);
  ForEachBlock(num_points, [&](int64_t block, int64_t begin, int64_t end) {
    std::vector<FaceSlot> table;
    std::vector<BoundaryFace>* out = boundary != nullptr ? &found[block] : nullptr;
    for (int64_t v = begin; v < end && v < first_bad.load(); ++v) {
      if (BucketIsManifold(static_cast<uint32_t>(v), uses.get() + start[v],
                           uses.get() + start[v + 1], table, out)) {
        continue;
      }
      int64_t cur = first_bad.load();
      while (v < cur && !first_bad.compare_exchange_weak(cur, v)) {
      }
      break;
    }
  });
  const int64_t v = first_bad.load();
  if (v == num_points) {
    if (boundary != nullptr) {
      boundary->clear();
      for (const std::vector<BoundaryFace>& f : found)
        boundary->insert(boundary->end(), f.begin(), f.end());
    }
    return absl::OkStatus();
  }
  // Two tets on the bad face with the same four vertices are one element listed twice: said so,
  // rather than as an overlap or a crowded face (found by a file-format sweep, on Gmsh 2 files,
  // which list an element once per physical group; client/io's Gmsh reader now keeps one copy).
  const auto duplicate = [&](const std::vector<int64_t>& on) -> std::optional<absl::Status> {
    for (size_t i = 0; i < on.size(); ++i) {
      for (size_t j = i + 1; j < on.size(); ++j) {
        Tet a = tets[on[i]], c = tets[on[j]];
        std::sort(a.begin(), a.end());
        std::sort(c.begin(), c.end());
        if (a != c) continue;
        return absl::InvalidArgumentError(absl::StrCat(
            "mesh.tets[", on[i], "] and mesh.tets[", on[j], "] are the same tet (vertices ", a[0],
            ", ", a[1], ", ", a[2], ", ", a[3], "): an element listed twice"));
      }
    }
    return std::nullopt;
  };
  // The bad bucket, sorted, names its first bad face; the tets on it are found again.
  FaceUse* b = uses.get() + start[v];
  FaceUse* e = uses.get() + start[v + 1];
  std::sort(b, e);
  for (FaceUse* p = b; p < e;) {
    FaceUse* q = p;
    while (q < e && FaceOf(*q) == FaceOf(*p)) ++q;
    const auto fb = static_cast<uint32_t>(*p >> 32);
    const auto fc = static_cast<uint32_t>((*p >> 1) & 0x7fffffffu);
    const std::string face = absl::StrCat("(", v, ", ", fb, ", ", fc, ")");
    if (q - p > 2) {
      const std::vector<int64_t> on =
          TetsOnFace(tets, {static_cast<uint32_t>(v), fb, fc}, static_cast<size_t>(q - p));
      if (std::optional<absl::Status> same = duplicate(on)) return *same;
      return absl::InvalidArgumentError(absl::StrCat(
          "mesh.tets: face ", face, " is shared by ", q - p, " tets (mesh.tets[", on.at(0), "], [",
          on.at(1), "], [", on.at(2), "]): a face may belong to at most two"));
    }
    if (q - p == 2 && FaceSide(p[0]) == FaceSide(p[1])) {
      const std::vector<int64_t> on = TetsOnFace(tets, {static_cast<uint32_t>(v), fb, fc}, 2);
      if (std::optional<absl::Status> same = duplicate(on)) return *same;
      return absl::InvalidArgumentError(absl::StrCat("mesh.tets[", on.at(0), "] and mesh.tets[",
                                                     on.at(1),
                                                     "] overlap: both lie on the same "
                                                     "side of their shared face ",
                                                     face));
    }
    p = q;
  }
  return absl::InternalError("face check disagreed with itself");
}

absl::Status CheckCoordinates(const std::vector<Vec3>& points) {
  // Finite is not enough: a tet's 6V multiplies three coordinate differences and its quality
  // squares that, so coordinates near 1e150 (found by the refine fuzzer) gave NaN volumes that
  // passed every check, and near 1e80 the overlap check's face grid, sized from NaN face boxes,
  // asked for more cells than memory holds (`tetrefine verify` aborted; found by a sweep,
  // 2026-11-28). Within +-1e30 (a parsec is 3e19 mm) every such product stays finite.
  constexpr double kMaxCoordinate = 1e30;
  const int64_t num_points = static_cast<int64_t>(points.size());
  const int64_t bad_point = FirstIndexWhere(num_points, [&](int64_t i) {
    const Vec3& p = points[i];
    return !(std::abs(p[0]) <= kMaxCoordinate && std::abs(p[1]) <= kMaxCoordinate &&
             std::abs(p[2]) <= kMaxCoordinate);
  });
  if (bad_point == num_points) return absl::OkStatus();
  const Vec3& p = points[bad_point];
  const bool finite = std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2]);
  return absl::InvalidArgumentError(absl::StrCat(
      "mesh.points[", bad_point, "] = ", Point(p),
      finite ? " is too large: coordinates must lie within +-1e30" : " is not finite"));
}

namespace {

// CheckConformity after CheckCoordinates has passed.
absl::Status ConformityOfCheckedPoints(const std::vector<Vec3>& points,
                                       const std::vector<Tet>& tets) {
  std::vector<BoundaryFace> boundary;
  if (absl::Status s = CheckFaces(points, tets, &boundary); !s.ok()) return s;
  return CheckBoundaryConformity(points, tets, boundary);
}

}  // namespace

absl::Status ValidateMesh(const Mesh& mesh, const Volume& volume, OutsidePolicy outside,
                          OrientationPolicy orientation, std::vector<Tet>* tets,
                          int64_t* reoriented) {
  const int64_t num_points = static_cast<int64_t>(mesh.points.size());
  if (mesh.tets.empty()) return absl::InvalidArgumentError("mesh.tets is empty");
  if (num_points > std::numeric_limits<uint32_t>::max() / 2) {
    return absl::InvalidArgumentError(
        absl::StrCat("mesh.points has ", num_points, " vertices; at most 2^31 are supported"));
  }
  if (absl::Status s = CheckCoordinates(mesh.points); !s.ok()) return s;
  const int64_t num_tets = static_cast<int64_t>(mesh.tets.size());
  const bool reject_inverted = orientation == OrientationPolicy::kReject;
  const int64_t bad_tet = FirstIndexWhere(num_tets, [&](int64_t t) {
    return InspectTet(mesh, mesh.tets[t], num_points, reject_inverted) != TetIssue::kNone;
  });
  if (bad_tet < num_tets) return DescribeTet(mesh, bad_tet, num_points);
  tets->clear();
  *reoriented = 0;
  if (!reject_inverted) {
    auto inverted = [&](const Tet& t) {
      return SignedVolume6(mesh.points[t[0]], mesh.points[t[1]], mesh.points[t[2]],
                           mesh.points[t[3]]) < 0.0;
    };
    const int64_t blocks = BlockCount(num_tets);
    std::vector<int64_t> flipped(blocks, 0);
    ForEachBlock(num_tets, [&](int64_t b, int64_t begin, int64_t end) {
      for (int64_t t = begin; t < end; ++t) flipped[b] += inverted(mesh.tets[t]);
    });
    for (int64_t f : flipped) *reoriented += f;
    // Copied only when something is flipped: a mesh can be large.
    if (*reoriented > 0) {
      *tets = mesh.tets;
      ForEachBlock(num_tets, [&](int64_t, int64_t begin, int64_t end) {
        for (int64_t t = begin; t < end; ++t) {
          if (inverted((*tets)[t])) std::swap((*tets)[t][2], (*tets)[t][3]);
        }
      });
    }
  }
  if (outside == OutsidePolicy::kReject) {
    const int64_t out = FirstIndexWhere(num_points, [&](int64_t i) {
      return !volume.Contains(volume.ContinuousIndex(mesh.points[i]));
    });
    if (out < num_points) {
      std::string box;
      Vec3 lo, hi;
      for (int a = 0; a < 3; ++a) {
        lo[a] = static_cast<double>(volume.lo()[a]);
        hi[a] = static_cast<double>(volume.hi()[a] - 1);
      }
      const std::array<Vec3, 2> world = WorldBounds(volume.grid(), lo, hi);
      for (int a = 0; a < 3; ++a) {
        absl::StrAppend(&box, a ? " x " : "", "[", world[0][a], ", ", world[1][a], "]");
      }
      // An oblique grid's sampled region is a parallelepiped: the box only bounds it, so the
      // message also gives the point's continuous index, which is what the test compares.
      std::string where;
      if (!volume.axis_aligned()) {
        const Vec3 u = volume.ContinuousIndex(mesh.points[out]);
        where = absl::StrCat(" (continuous index ", Point(u), ", sampled index box ", Point(lo),
                             " to ", Point(hi), ")");
      }
      return absl::InvalidArgumentError(
          absl::StrCat("mesh.points[", out, "] = ", Point(mesh.points[out]),
                       " lies outside the volume's sampled box ", box, where));
    }
  }
  // The coordinates were checked first thing.
  return ConformityOfCheckedPoints(mesh.points, tets->empty() ? mesh.tets : *tets);
}

absl::Status CheckConformity(const std::vector<Vec3>& points, const std::vector<Tet>& tets) {
  if (absl::Status s = CheckCoordinates(points); !s.ok()) return s;
  return ConformityOfCheckedPoints(points, tets);
}

}  // namespace tetrefine
