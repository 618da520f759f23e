#include "core/boundary_conformity.h"

#include <algorithm>
#include <atomic>
#include <bit>
#include <cmath>
#include <initializer_list>
#include <limits>
#include <memory>
#include <string>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "core/counting_sort.h"
#include "core/fill_later.h"
#include "core/parallel.h"
#include "core/sorted_tet.h"
#include "core/tet_overlap.h"
#include "core/tet_topology.h"
#include "core/vec3_ops.h"

namespace tetrefine {
namespace {

constexpr double kRelativeTolerance = 1e-13;
// How many roundings of the coordinates' magnitude a vertex may be off a face and still be on
// it: a midpoint or a centroid is exact only to half an ulp, and the distance itself is computed
// from coordinate differences.
constexpr double kRoundings = 8.0;

// Squared distance from p to the closed triangle (a, b, c), by the Voronoi regions of its
// corners, edges and interior (Ericson, Real-Time Collision Detection, 5.1.5).
double DistanceToTriangle2(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 ab = Sub(b, a), ac = Sub(c, a), ap = Sub(p, a);
  const double d1 = Dot(ab, ap), d2 = Dot(ac, ap);
  if (d1 <= 0.0 && d2 <= 0.0) return Norm2(ap);
  const Vec3 bp = Sub(p, b);
  const double d3 = Dot(ab, bp), d4 = Dot(ac, bp);
  if (d3 >= 0.0 && d4 <= d3) return Norm2(bp);
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) return Norm2(Axpy(-d1 / (d1 - d3), ab, ap));
  const Vec3 cp = Sub(p, c);
  const double d5 = Dot(ab, cp), d6 = Dot(ac, cp);
  if (d6 >= 0.0 && d5 <= d6) return Norm2(cp);
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) return Norm2(Axpy(-d2 / (d2 - d6), ac, ap));
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0.0 && d4 - d3 >= 0.0 && d5 - d6 >= 0.0) {
    return Norm2(Axpy(-(d4 - d3) / ((d4 - d3) + (d5 - d6)), Sub(c, b), bp));
  }
  const double denom = 1.0 / (va + vb + vc);
  return Norm2(Axpy(-vc * denom, ac, Axpy(-vb * denom, ab, ap)));
}

// A boundary face's box, grown by its tolerance, and the grid level it is filed under.
struct FaceBox {
  Vec3 lo, hi;
  double tolerance;
  int level;
};

// A hash grid with one level per power of two of cell size: a face is filed under the level
// whose cells are at least as wide as its box, so it lands in at most 2 x 2 x 2 cells (3 when
// rounding puts a box edge just on a cell wall), whatever the spread of face sizes; a vertex
// looks in its one cell on each level that holds faces. Cells map to buckets (Bucket); faces of
// other cells that share a bucket are weeded out by their boxes.
class FaceGrid {
 public:
  FaceGrid(const std::vector<Vec3>& points, const std::vector<BoundaryFace>& boundary) {
    const int64_t n = static_cast<int64_t>(boundary.size());
    boxes_.resize(n);
    ForEachBlock(n, [&](int64_t, int64_t begin, int64_t end) {
      for (int64_t f = begin; f < end; ++f) boxes_[f] = Box(points, boundary[f]);
    });
    origin_ = boxes_[0].lo;
    double smallest = std::numeric_limits<double>::infinity();
    Vec3 top = boxes_[0].hi;
    for (const FaceBox& b : boxes_) {
      for (int a = 0; a < 3; ++a) {
        origin_[a] = std::min(origin_[a], b.lo[a]);
        top[a] = std::max(top[a], b.hi[a]);
      }
      smallest = std::min(smallest, Width(b));
    }
    const double extent = std::max({top[0] - origin_[0], top[1] - origin_[1], top[2] - origin_[2]});
    // The finest level is no finer than 2^-40 of the extent, so cell numbers stay exact in a
    // double and small in an int64; faces smaller than that share level 0.
    cell0_ = std::max({smallest, std::ldexp(extent, -40), std::numeric_limits<double>::min()});
    for (FaceBox& b : boxes_) {
      const double w = Width(b);
      while (b.level < kMaxLevel && CellSize(b.level) < w) ++b.level;
      levels_ |= uint64_t{1} << b.level;
    }
    // A counting sort of (cell, face) entries into buckets, faces in index order within each.
    uint64_t entries = 0;
    for (int64_t f = 0; f < n; ++f) ForEachCell(f, [&](uint64_t) { ++entries; });
    // About four entries a bucket: the offsets stay small enough to be cached, and a bucket
    // still holds few faces.
    const uint64_t buckets = std::bit_ceil(std::max<uint64_t>(entries / 4, 64));
    mask_ = buckets - 1;
    // Counted at the bucket's end, summed to where the bucket ends, then filled backwards, so
    // each bucket lists its faces in index order and no second offset array is needed.
    start_.assign(buckets + 1, 0);
    for (int64_t f = 0; f < n; ++f) ForEachCell(f, [&](uint64_t k) { ++start_[k]; });
    for (uint64_t k = 1; k <= buckets; ++k) start_[k] += start_[k - 1];
    faces_.resize(entries);
    for (int64_t f = n - 1; f >= 0; --f) {
      ForEachCell(f, [&](uint64_t k) { faces_[--start_[k]] = static_cast<uint32_t>(f); });
    }
  }

  // Calls visit(face) for every face whose grown box may hold p (and some that do not).
  template <typename Visit>
  void ForEachNear(const Vec3& p, Visit visit) const {
    for (uint64_t levels = levels_; levels != 0; levels &= levels - 1) {
      const int level = std::countr_zero(levels);
      const double h = CellSize(level);
      const uint64_t k = Bucket(level, Cell(p[0], origin_[0], h), Cell(p[1], origin_[1], h),
                                Cell(p[2], origin_[2], h));
      for (uint64_t e = start_[k]; e < start_[k + 1]; ++e) visit(faces_[e]);
    }
  }

  const FaceBox& box(uint32_t f) const { return boxes_[f]; }

 private:
  static constexpr int kMaxLevel = 62;

  static FaceBox Box(const std::vector<Vec3>& points, const BoundaryFace& face) {
    const Vec3& a = points[face[0]];
    const Vec3& b = points[face[1]];
    const Vec3& c = points[face[2]];
    const double longest =
        std::sqrt(std::max({Norm2(Sub(a, b)), Norm2(Sub(b, c)), Norm2(Sub(c, a))}));
    double magnitude = 0.0;
    for (int i = 0; i < 3; ++i) {
      magnitude = std::max({magnitude, std::abs(a[i]), std::abs(b[i]), std::abs(c[i])});
    }
    FaceBox box;
    box.tolerance = kRelativeTolerance * longest +
                    kRoundings * std::numeric_limits<double>::epsilon() * magnitude;
    for (int i = 0; i < 3; ++i) {
      box.lo[i] = std::min({a[i], b[i], c[i]}) - box.tolerance;
      box.hi[i] = std::max({a[i], b[i], c[i]}) + box.tolerance;
    }
    box.level = 0;
    return box;
  }

  static double Width(const FaceBox& b) {
    return std::max({b.hi[0] - b.lo[0], b.hi[1] - b.lo[1], b.hi[2] - b.lo[2]});
  }

  double CellSize(int level) const { return std::ldexp(cell0_, level); }

  // Clamped, so a point and a box that holds it agree on the cell even where the division
  // rounds (clamping is monotone). NaN (coordinates near the double range, which verify
  // reads; ValidateMesh refuses them first) goes to the lowest cell rather than to a cast's
  // undefined behaviour.
  static int64_t Cell(double x, double origin, double h) {
    const double c = std::floor((x - origin) / h);
    if (!(c >= -4.0)) return -4;
    return static_cast<int64_t>(std::min(c, 0x1p50));
  }

  // The cell's Morton code (21 bits per axis, interleaved), offset per level, modulo the bucket
  // count: neighbouring cells land in nearby buckets, so building and querying in a spatially
  // coherent order (faces and vertices of a mesh mostly are) stays in cache. Far cells that
  // share a bucket cost a box test each.
  static uint64_t Spread(int64_t c) {
    uint64_t x = static_cast<uint64_t>(c) & 0x1fffff;
    x = (x | x << 32) & 0x1f00000000ffffull;
    x = (x | x << 16) & 0x1f0000ff0000ffull;
    x = (x | x << 8) & 0x100f00f00f00f00full;
    x = (x | x << 4) & 0x10c30c30c30c30c3ull;
    x = (x | x << 2) & 0x1249249249249249ull;
    return x;
  }
  uint64_t Bucket(int level, int64_t i, int64_t j, int64_t k) const {
    const uint64_t morton = Spread(i) | Spread(j) << 1 | Spread(k) << 2;
    return (morton + static_cast<uint64_t>(level) * 0x9E3779B97F4A7C15ull) & mask_;
  }

  template <typename Body>
  void ForEachCell(int64_t f, Body body) const {
    const FaceBox& b = boxes_[f];
    const double h = CellSize(b.level);
    int64_t lo[3], hi[3];
    for (int a = 0; a < 3; ++a) {
      lo[a] = Cell(b.lo[a], origin_[a], h);
      // A box no wider than its level's cells spans at most three of them; the bound only
      // matters where the arithmetic overflowed.
      hi[a] = std::clamp(Cell(b.hi[a], origin_[a], h), lo[a], lo[a] + 2);
    }
    for (int64_t i = lo[0]; i <= hi[0]; ++i) {
      for (int64_t j = lo[1]; j <= hi[1]; ++j) {
        for (int64_t k = lo[2]; k <= hi[2]; ++k) body(Bucket(b.level, i, j, k));
      }
    }
  }

  FillLater<FaceBox> boxes_;  // every one written by the constructor's first pass
  Vec3 origin_{};
  double cell0_ = 1.0;
  uint64_t levels_ = 0;          // bit l: some face is filed under level l
  uint64_t mask_ = 0;            // bucket count - 1 (a power of two)
  std::vector<uint64_t> start_;  // bucket k holds faces_[start_[k], start_[k + 1])
  std::vector<uint32_t> faces_;
};

// A boundary vertex found on a boundary face it is not a vertex of.
struct Hit {
  uint32_t vertex;
  uint32_t face;  // index into the boundary list
};

// The first tet, in index order, that has all of face's vertices.
int64_t TetOnFace(const std::vector<Tet>& tets, const BoundaryFace& face) {
  return FirstIndexWhere(static_cast<int64_t>(tets.size()), [&](int64_t t) {
    const Tet& tet = tets[t];
    return std::all_of(face.begin(), face.end(), [&](uint32_t v) {
      return std::find(tet.begin(), tet.end(), v) != tet.end();
    });
  });
}

// For each of `quads` (four vertex ids, any order), whether some tet has exactly those vertices.
// The checks' candidates are rare, so this one pass over the tets runs only when there are any.
// Each flag has one writer: two tets with the same vertices failed the face check.
std::vector<uint8_t> AreTets(const std::vector<Tet>& tets,
                             const std::vector<std::array<uint32_t, 4>>& quads) {
  std::vector<std::pair<std::array<uint32_t, 4>, int64_t>> sorted(quads.size());
  for (size_t i = 0; i < quads.size(); ++i) {
    sorted[i] = {quads[i], static_cast<int64_t>(i)};
    std::sort(sorted[i].first.begin(), sorted[i].first.end());
  }
  std::sort(sorted.begin(), sorted.end());
  std::vector<uint8_t> is_tet(quads.size(), 0);
  ForEachBlock(static_cast<int64_t>(tets.size()), [&](int64_t, int64_t begin, int64_t end) {
    for (int64_t t = begin; t < end; ++t) {
      const std::array<uint32_t, 4> q = SortTet(tets[t]).v;
      auto it = std::lower_bound(sorted.begin(), sorted.end(), std::make_pair(q, int64_t{-1}));
      for (; it != sorted.end() && it->first == q; ++it) is_tet[it->second] = 1;
    }
  });
  return is_tet;
}

std::string FaceName(const BoundaryFace& f) {
  return absl::StrCat("(", f[0], ", ", f[1], ", ", f[2], ")");
}

absl::Status CheckNoVertexOnFace(const std::vector<Vec3>& points, const std::vector<Tet>& tets,
                                 const std::vector<BoundaryFace>& boundary) {
  const int64_t num_points = static_cast<int64_t>(points.size());
  std::vector<uint8_t> on_boundary(num_points, 0);
  for (const BoundaryFace& f : boundary) {
    for (uint32_t v : f) on_boundary[v] = 1;
  }
  std::vector<uint32_t> vertices;
  for (int64_t v = 0; v < num_points; ++v) {
    if (on_boundary[v]) vertices.push_back(static_cast<uint32_t>(v));
  }
  const FaceGrid grid(points, boundary);
  const int64_t n = static_cast<int64_t>(vertices.size());
  std::vector<std::vector<Hit>> found(BlockCount(n));
  // As the overlap check (core/tet_overlap.cc CheckOverlaps): a few faces near each vertex on a
  // mesh, but quadratic on a valid one whose thin faces all meet near each other (20,000
  // slivers around one edge: 40,000 boundary faces, 1.7 s of a 2 s check; an outside review,
  // 2026-11-28). Past the bound the mesh is refused, the same whatever the thread count.
  CrowdedPairBudget pairs(n);
  ForEachBlock(n, [&](int64_t block, int64_t begin, int64_t end) {
    int64_t mine_pairs = 0;
    for (int64_t i = begin; i < end; ++i) {
      if (!pairs.Flush(mine_pairs)) return;
      const uint32_t w = vertices[i];
      const Vec3& p = points[w];
      grid.ForEachNear(p, [&](uint32_t f) {
        ++mine_pairs;
        const BoundaryFace& face = boundary[f];
        if (face[0] == w || face[1] == w || face[2] == w) return;
        const FaceBox& b = grid.box(f);
        for (int a = 0; a < 3; ++a) {
          if (p[a] < b.lo[a] || p[a] > b.hi[a]) return;
        }
        const double d2 = DistanceToTriangle2(p, points[face[0]], points[face[1]], points[face[2]]);
        if (d2 <= b.tolerance * b.tolerance) found[block].push_back({w, f});
      });
    }
    pairs.Finish(mine_pairs);
  });
  if (pairs.Exceeded()) {
    return CrowdedMeshError(tets, "vertex and a boundary face meet near each other", pairs.max());
  }
  std::vector<Hit> hits;
  for (const std::vector<Hit>& h : found) hits.insert(hits.end(), h.begin(), h.end());
  if (hits.empty()) return absl::OkStatus();
  // A face's own tet's fourth vertex may come within tolerance of it (a sliver), and that is no
  // hanging node: drop the hits whose vertex and face make up a tet (a boundary face has one).
  std::vector<std::array<uint32_t, 4>> quads(hits.size());
  for (size_t i = 0; i < hits.size(); ++i) {
    const BoundaryFace& f = boundary[hits[i].face];
    quads[i] = {f[0], f[1], f[2], hits[i].vertex};
  }
  const std::vector<uint8_t> own = AreTets(tets, quads);
  const Hit* first = nullptr;
  for (size_t i = 0; i < hits.size(); ++i) {
    if (own[i]) continue;
    const Hit& h = hits[i];
    if (first == nullptr || h.vertex < first->vertex ||
        (h.vertex == first->vertex && boundary[h.face] < boundary[first->face])) {
      first = &h;
    }
  }
  if (first == nullptr) return absl::OkStatus();
  const BoundaryFace& face = boundary[first->face];
  const Vec3& p = points[first->vertex];
  return absl::InvalidArgumentError(absl::StrCat(
      "mesh is not conformal: vertex ", first->vertex,
      absl::StrFormat(" at (%g, %g, %g)", p[0], p[1], p[2]), " lies on boundary face ",
      FaceName(face), " of mesh.tets[", TetOnFace(tets, face),
      "] without being one of its vertices (a hanging node, or two boundary faces that overlap "
      "inside the mesh)"));
}

// Two boundary faces (u, v, c) and (u, v, d) folded onto each other: d lies in the plane of
// (u, v, c), within the tolerance FaceGrid uses, on the same side of the edge as c. In a
// conformal mesh a face is either shared whole or on the boundary, so two boundary faces that
// overlap in their plane are two tets meeting over part of a face: a quadrilateral split by
// different diagonals on its two sides (two triangulations of one planar region always
// disagree on some edge of the region's outline, where their two triangles fold like this).
// Real boundaries that fold back at an angle of zero are not valid meshes either.
bool Folded(const Vec3& u, const Vec3& v, const Vec3& c, const Vec3& d) {
  const Vec3 e = Sub(v, u), uc = Sub(c, u), ud = Sub(d, u);
  const Vec3 n = Cross(e, uc);
  const double longest =
      std::sqrt(std::max({Norm2(e), Norm2(uc), Norm2(ud), Norm2(Sub(c, v)), Norm2(Sub(d, v))}));
  double magnitude = 0.0;
  for (int i = 0; i < 3; ++i) {
    magnitude =
        std::max({magnitude, std::abs(u[i]), std::abs(v[i]), std::abs(c[i]), std::abs(d[i])});
  }
  const double tolerance = kRelativeTolerance * longest +
                           kRoundings * std::numeric_limits<double>::epsilon() * magnitude;
  const double n_norm = std::sqrt(Norm2(n));
  if (!(std::abs(Dot(n, ud)) <= tolerance * n_norm)) return false;
  const double ee = Norm2(e);
  if (!(ee > 0.0)) return false;
  const Vec3 c_off = Axpy(-Dot(uc, e) / ee, e, uc);  // c's offset from the edge's line
  const Vec3 d_off = Axpy(-Dot(ud, e) / ee, e, ud);
  return Dot(c_off, d_off) > 0.0;
}

// The boundary's edges, each with the third vertex of every boundary face on it: the closed
// check and the fold check read the same lists.
class BoundaryEdges {
 public:
  BoundaryEdges(int64_t num_points, const std::vector<BoundaryFace>& boundary) {
    // Each edge (u < v) of a boundary face, filed under u as (v, third vertex) in one word, so
    // that sorting a bucket groups an edge's faces.
    auto key = [](uint32_t v, uint32_t w) { return uint64_t{v} << 32 | w; };
    BucketLayout layout = CountingSort(
        static_cast<int64_t>(boundary.size()), num_points,
        [&](int64_t f, auto add) {
          add(boundary[f][0], 2);
          add(boundary[f][1], 1);
        },
        [&](uint64_t total) { ends_.reset(new uint64_t[total]); },
        [&](int64_t f, auto slot) {
          const BoundaryFace& face = boundary[f];
          uint64_t* out = ends_.get() + slot(face[0], 2);
          out[0] = key(face[1], face[2]);
          out[1] = key(face[2], face[1]);
          ends_[slot(face[1], 1)] = key(face[2], face[0]);
        });
    start_ = std::move(layout.start);
    // Sorted once, here, so that every check after reads the buckets from any thread.
    ForEachBlock(num_points, [&](int64_t, int64_t begin, int64_t end) {
      for (int64_t u = begin; u < end; ++u) {
        SortSmall(ends_.get() + start_[u], ends_.get() + start_[u + 1]);
      }
    });
  }

  // Calls visit(v, thirds, count) for each edge (u, v), v ascending, with the third vertices of
  // its `count` faces; stops at the first visit that returns true and returns that.
  template <typename Visit>
  bool ForEachEdgeOf(int64_t u, Visit visit) const {
    const uint64_t* b = ends_.get() + start_[u];
    const uint64_t* e = ends_.get() + start_[u + 1];
    uint32_t thirds[64];
    for (const uint64_t* p = b; p < e;) {
      const uint64_t* q = p;
      while (q < e && (*q >> 32) == (*p >> 32)) ++q;
      const int64_t count = q - p;
      // More than 64 faces on one edge only happens in a broken mesh; the fold check looks at
      // the first 64 of them, the count is exact.
      const int64_t kept = std::min<int64_t>(count, 64);
      for (int64_t i = 0; i < kept; ++i) thirds[i] = static_cast<uint32_t>(p[i]);
      if (visit(static_cast<uint32_t>(*p >> 32), thirds, kept, count)) return true;
      p = q;
    }
    return false;
  }

  // Whether (u, v, third) is a boundary face, u < v.
  bool HasFace(uint32_t u, uint32_t v, uint32_t third) const {
    const uint64_t* b = ends_.get() + start_[u];
    const uint64_t* e = ends_.get() + start_[u + 1];
    return std::binary_search(b, e, uint64_t{v} << 32 | third);
  }

 private:
  std::unique_ptr<uint64_t[]> ends_;
  FillLater<uint64_t> start_;  // bucket u holds ends_[start_[u], start_[u + 1])
};

// The smallest boundary face, in id order, with all of `ids`.
const BoundaryFace* SmallestFaceWith(const std::vector<BoundaryFace>& boundary,
                                     std::initializer_list<uint32_t> ids) {
  const BoundaryFace* face = nullptr;
  for (const BoundaryFace& f : boundary) {
    const bool all = std::all_of(ids.begin(), ids.end(), [&](uint32_t id) {
      return f[0] == id || f[1] == id || f[2] == id;
    });
    if (all && (face == nullptr || f < *face)) face = &f;
  }
  return face;
}

BoundaryFace SortedFace(uint32_t a, uint32_t b, uint32_t c) {
  BoundaryFace f = {a, b, c};
  std::sort(f.begin(), f.end());
  return f;
}

absl::Status CheckClosed(const std::vector<Tet>& tets, const std::vector<BoundaryFace>& boundary,
                         const BoundaryEdges& edges, int64_t num_points) {
  // The bucket's first edge used by an odd number of faces, as (other end, uses).
  auto first_odd = [&](int64_t u) -> std::pair<uint32_t, int64_t> {
    std::pair<uint32_t, int64_t> odd{0, 0};
    edges.ForEachEdgeOf(u, [&](uint32_t v, const uint32_t*, int64_t, int64_t count) {
      if (count % 2 == 0) return false;
      odd = {v, count};
      return true;
    });
    return odd;
  };
  const int64_t u =
      FirstIndexWhere(num_points, [&](int64_t u) { return first_odd(u).second != 0; });
  if (u == num_points) return absl::OkStatus();
  const auto [v, uses] = first_odd(u);
  const BoundaryFace* face = SmallestFaceWith(boundary, {static_cast<uint32_t>(u), v});
  return absl::InvalidArgumentError(
      absl::StrCat("mesh is not conformal: edge (", u, ", ", v, ") lies on ", uses,
                   " boundary faces, an odd number (one is face ", FaceName(*face),
                   " of mesh.tets[", TetOnFace(tets, *face),
                   "]), so the boundary is not closed: a hanging node on the edge, or a crack"));
}

// Every (u, v, c, d) with u < v and c < d where (u, v, c) and (u, v, d) are boundary faces and
// keep(u, v, c, d) holds, in an order that does not depend on the thread count.
template <typename Keep>
std::vector<std::array<uint32_t, 4>> FacePairsWhere(int64_t num_points, const BoundaryEdges& edges,
                                                    Keep keep) {
  std::vector<std::vector<std::array<uint32_t, 4>>> found(BlockCount(num_points));
  ForEachBlock(num_points, [&](int64_t block, int64_t begin, int64_t end) {
    for (int64_t u = begin; u < end; ++u) {
      edges.ForEachEdgeOf(u, [&](uint32_t v, const uint32_t* thirds, int64_t kept, int64_t) {
        for (int64_t i = 0; i < kept; ++i) {
          for (int64_t j = i + 1; j < kept; ++j) {
            const uint32_t c = std::min(thirds[i], thirds[j]), d = std::max(thirds[i], thirds[j]);
            if (c != d && keep(static_cast<uint32_t>(u), v, c, d)) {
              found[block].push_back({static_cast<uint32_t>(u), v, c, d});
            }
          }
        }
        return false;
      });
    }
  });
  std::vector<std::array<uint32_t, 4>> all;
  for (const auto& f : found) all.insert(all.end(), f.begin(), f.end());
  return all;
}

absl::Status CheckNoFold(const std::vector<Vec3>& points, const std::vector<Tet>& tets,
                         const BoundaryEdges& edges) {
  // A folded pair: edge (u, v), third vertices c < d.
  using Fold = std::array<uint32_t, 4>;
  const std::vector<Fold> folds =
      FacePairsWhere(static_cast<int64_t>(points.size()), edges,
                     [&](uint32_t u, uint32_t v, uint32_t c, uint32_t d) {
                       return Folded(points[u], points[v], points[c], points[d]);
                     });
  if (folds.empty()) return absl::OkStatus();
  // Two faces of one tet fold onto each other when the tet is a sliver flat within the
  // tolerance; that tet is valid (ValidateMesh judges its volume): drop those.
  const std::vector<uint8_t> own = AreTets(tets, folds);
  const Fold* first = nullptr;
  for (size_t i = 0; i < folds.size(); ++i) {
    if (!own[i] && (first == nullptr || folds[i] < *first)) first = &folds[i];
  }
  if (first == nullptr) return absl::OkStatus();
  const auto [u, v, c, d] = *first;
  const BoundaryFace a = SortedFace(u, v, c), b = SortedFace(u, v, d);
  return absl::InvalidArgumentError(absl::StrCat(
      "mesh is not conformal: boundary faces ", FaceName(a), " of mesh.tets[", TetOnFace(tets, a),
      "] and ", FaceName(b), " of mesh.tets[", TetOnFace(tets, b),
      "] lie in one plane on the same side of their common edge (", u, ", ", v,
      "), so two tets meet over part of a face (crossing diagonals: a quadrilateral split "
      "differently on its two sides, or a boundary folded onto itself)"));
}

// The vertex opposite each of `faces` (ascending ids) in its tet, and that tet, for faces of
// exactly one tet (boundary faces): one pass over the tets, run only for the rare candidates.
struct Owner {
  uint32_t opposite = 0;
  int64_t tet = -1;
};
std::vector<Owner> OwnersOf(const std::vector<Tet>& tets, const std::vector<BoundaryFace>& faces) {
  std::vector<std::pair<BoundaryFace, int64_t>> sorted(faces.size());
  for (size_t i = 0; i < faces.size(); ++i) sorted[i] = {faces[i], static_cast<int64_t>(i)};
  std::sort(sorted.begin(), sorted.end());
  std::vector<Owner> owners(faces.size());
  ForEachBlock(static_cast<int64_t>(tets.size()), [&](int64_t, int64_t begin, int64_t end) {
    for (int64_t t = begin; t < end; ++t) {
      for (int skip = 0; skip < 4; ++skip) {
        const auto [a, b, c] = kTetFaces[skip];
        const BoundaryFace f = SortedFace(tets[t][a], tets[t][b], tets[t][c]);
        auto it = std::lower_bound(sorted.begin(), sorted.end(), std::make_pair(f, int64_t{-1}));
        for (; it != sorted.end() && it->first == f; ++it) owners[it->second] = {tets[t][skip], t};
      }
    }
  });
  return owners;
}

// Four boundary faces that make up the surface of a tet (u, v, c, d) the mesh does not have
// enclose either a cavity or tets of their own (a tet split at an inner point, alone), both
// valid; or two tets that overlap: a quadrilateral that is not planar, split along one diagonal
// on one side and the other diagonal on the other, where the two sides bulge into each other
// (where they bulge apart they leave a tet-shaped cavity, which is a valid mesh). The overlap
// shows in a face's own tet: on the shell's inner side of the face, yet with its fourth vertex
// outside the shell, so it reaches through the shell's other faces. Check 3 finds the planar
// case (the faces fold); this one the rest. Returns the offending shell's tet through the face,
// or nothing.
absl::Status CheckNoOverlappingShell(const std::vector<Vec3>& points, const std::vector<Tet>& tets,
                                     const BoundaryEdges& edges) {
  using Shell = std::array<uint32_t, 4>;  // ascending
  // Each shell once: from the edge of its two smallest vertices.
  const std::vector<Shell> shells =
      FacePairsWhere(static_cast<int64_t>(points.size()), edges,
                     [&](uint32_t u, uint32_t v, uint32_t c, uint32_t d) {
                       return v < c && edges.HasFace(c, d, u) && edges.HasFace(c, d, v);
                     });
  if (shells.empty()) return absl::OkStatus();
  // A single tet alone is its own shell.
  const std::vector<uint8_t> is_tet = AreTets(tets, shells);
  std::vector<Shell> open;
  for (size_t i = 0; i < shells.size(); ++i) {
    if (!is_tet[i]) open.push_back(shells[i]);
  }
  if (open.empty()) return absl::OkStatus();
  std::sort(open.begin(), open.end());
  // Face f of a shell is the one opposite its vertex f (ascending, as the shell is).
  std::vector<BoundaryFace> faces;
  for (const Shell& s : open) {
    for (const auto& [a, b, c] : kTetFaces) faces.push_back({s[a], s[b], s[c]});
  }
  const std::vector<Owner> owners = OwnersOf(tets, faces);
  for (size_t n = 0; n < open.size(); ++n) {
    const Shell& s = open[n];
    const Vec3* p[4] = {&points[s[0]], &points[s[1]], &points[s[2]], &points[s[3]]};
    // 6 x the volume of (face f, q): its sign says which side of face f q is on.
    auto side = [&](int f, const Vec3& q) {
      const auto [a, b, c] = kTetFaces[f];
      return SignedVolume6(*p[a], *p[b], *p[c], q);
    };
    // The shell's inside is on the side of the vertex off each face.
    std::array<double, 4> inside;
    for (int f = 0; f < 4; ++f) inside[f] = side(f, *p[f]);
    for (int skip = 0; skip < 4; ++skip) {
      const Owner& owner = owners[4 * n + static_cast<size_t>(skip)];
      const Vec3& o = points[owner.opposite];
      double longest2 = 0.0;
      for (int i = 0; i < 4; ++i) {
        longest2 = std::max(longest2, Norm2(Sub(o, *p[i])));
        for (int j = i + 1; j < 4; ++j) longest2 = std::max(longest2, Norm2(Sub(*p[i], *p[j])));
      }
      // The degenerate-tet bound ValidateMesh uses: |6V| <= 1e-12 L^3.
      const double tolerance = 1e-12 * longest2 * std::sqrt(longest2);
      const double a = side(skip, o);
      // On the outer side of its face: a cavity, the tet is outside the shell.
      if (!(inside[skip] > 0.0 ? a > tolerance : a < -tolerance)) continue;
      bool outside = false;
      for (int other = 0; other < 4; ++other) {
        const double b = side(other, o);
        if (inside[other] > 0.0 ? b < -tolerance : b > tolerance) outside = true;
      }
      if (!outside) continue;  // the shell holds its own tets
      const BoundaryFace& face = faces[4 * n + static_cast<size_t>(skip)];
      return absl::InvalidArgumentError(absl::StrCat(
          "mesh is not conformal: boundary faces on vertices (", s[0], ", ", s[1], ", ", s[2], ", ",
          s[3], ") close around a tet the mesh does not have, and mesh.tets[", owner.tet,
          "], on the inside of face ", FaceName(face),
          ", reaches out through the others, so "
          "two tets overlap (crossing diagonals: a quadrilateral that is not planar split "
          "differently on its two sides)"));
    }
  }
  return absl::OkStatus();
}

// Every boundary face with its tet, by tet then face. Only faces whose three corners are all on
// the boundary can be boundary faces: most tets are passed over on those flags.
std::vector<OwnedFace> OwnedFaces(int64_t num_points, const std::vector<Tet>& tets,
                                  const std::vector<BoundaryFace>& boundary,
                                  const BoundaryEdges& edges) {
  std::vector<uint8_t> on_boundary(num_points, 0);
  for (const BoundaryFace& f : boundary) {
    for (uint32_t v : f) on_boundary[v] = 1;
  }
  const int64_t n = static_cast<int64_t>(tets.size());
  std::vector<std::vector<OwnedFace>> found(BlockCount(n));
  ForEachBlock(n, [&](int64_t block, int64_t begin, int64_t end) {
    for (int64_t t = begin; t < end; ++t) {
      const Tet& tet = tets[t];
      if (on_boundary[tet[0]] + on_boundary[tet[1]] + on_boundary[tet[2]] + on_boundary[tet[3]] <
          3) {
        continue;
      }
      for (const auto& [a, b, c] : kTetFaces) {
        const BoundaryFace f = SortedFace(tet[a], tet[b], tet[c]);
        if (on_boundary[f[0]] && on_boundary[f[1]] && on_boundary[f[2]] &&
            edges.HasFace(f[0], f[1], f[2])) {
          found[block].push_back({f, t});
        }
      }
    }
  });
  std::vector<OwnedFace> faces;
  faces.reserve(boundary.size());
  for (const std::vector<OwnedFace>& f : found) faces.insert(faces.end(), f.begin(), f.end());
  return faces;
}

}  // namespace

absl::Status CheckBoundaryConformity(const std::vector<Vec3>& points, const std::vector<Tet>& tets,
                                     const std::vector<BoundaryFace>& boundary) {
  if (boundary.empty()) return absl::OkStatus();
  if (absl::Status s = CheckNoVertexOnFace(points, tets, boundary); !s.ok()) return s;
  BoundaryEdges edges(static_cast<int64_t>(points.size()), boundary);
  if (absl::Status s = CheckClosed(tets, boundary, edges, static_cast<int64_t>(points.size()));
      !s.ok()) {
    return s;
  }
  if (absl::Status s = CheckNoFold(points, tets, edges); !s.ok()) return s;
  if (absl::Status s = CheckNoOverlappingShell(points, tets, edges); !s.ok()) return s;
  return CheckNoOverlappingTets(
      points, tets, OwnedFaces(static_cast<int64_t>(points.size()), tets, boundary, edges));
}

}  // namespace tetrefine
