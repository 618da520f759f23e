#include "core/tet_overlap.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <memory>
#include <mutex>
#include <numeric>
#include <string>
#include <utility>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "core/parallel.h"
#include "core/tet_topology.h"

namespace tetrefine {
// A named namespace, not an anonymous one: a unity build compiles this file together with
// boundary_conformity.cc, whose file-local Sub and Dot would clash with these.
namespace tet_overlap_internal {
namespace {

constexpr double kEps = std::numeric_limits<double>::epsilon();
// Contact within 1e-10 of the pair's size is not an overlap: well above the rounding of the
// coordinates (check 1 takes 1e-13 for a vertex on a face) and well below any overlap a mesh
// generator or a mistaken merge produces.
constexpr double kRelativeSlack = 1e-10;

Vec3 Sub(const Vec3& a, const Vec3& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
double Dot(const Vec3& a, const Vec3& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
Vec3 Cross(const Vec3& a, const Vec3& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}
double Norm(const Vec3& a) { return std::sqrt(Dot(a, a)); }

struct Box {
  Vec3 lo, hi;
};

Box BoxOf(const std::array<Vec3, 4>& p, double grow) {
  Box b{p[0], p[0]};
  for (int i = 1; i < 4; ++i) {
    for (int a = 0; a < 3; ++a) {
      b.lo[a] = std::min(b.lo[a], p[i][a]);
      b.hi[a] = std::max(b.hi[a], p[i][a]);
    }
  }
  for (int a = 0; a < 3; ++a) {
    b.lo[a] -= grow;
    b.hi[a] += grow;
  }
  return b;
}

bool Meet(const Box& a, const Box& b) {
  for (int i = 0; i < 3; ++i) {
    if (a.hi[i] < b.lo[i] || b.hi[i] < a.lo[i]) return false;
  }
  return true;
}

std::array<Vec3, 4> Corners(const std::vector<Vec3>& points, const Tet& t) {
  return {points[t[0]], points[t[1]], points[t[2]], points[t[3]]};
}

// What the separating-axis test reads of a tet, computed once per tet: its corners, and for
// each face f (opposite corner f) the normal n = u x v of two of its edges, |n|, |u| |v| (the
// scale of n's rounding) and the tet's own projection on n.
struct TetAxes {
  std::array<Vec3, 4> p;
  std::array<Vec3, 4> n;
  std::array<double, 4> n_len, n_scale, lo, hi;
  double longest = 0.0;    // longest edge
  double magnitude = 0.0;  // largest coordinate magnitude
};

TetAxes AxesOf(const std::array<Vec3, 4>& p) {
  TetAxes t;
  t.p = p;
  for (int e = 0; e < 6; ++e) {
    t.longest = std::max(t.longest, Norm(Sub(p[kTetEdges[e][1]], p[kTetEdges[e][0]])));
  }
  for (const Vec3& q : p) {
    t.magnitude = std::max({t.magnitude, std::abs(q[0]), std::abs(q[1]), std::abs(q[2])});
  }
  for (int f = 0; f < 4; ++f) {
    const auto [i, j, k] = kTetFaces[f];
    const Vec3 u = Sub(p[j], p[i]), v = Sub(p[k], p[i]);
    t.n[f] = Cross(u, v);
    t.n_len[f] = Norm(t.n[f]);
    t.n_scale[f] = Norm(u) * Norm(v);
    const double on_face = Dot(t.n[f], p[i]), off = Dot(t.n[f], p[f]);
    t.lo[f] = std::min(on_face, off);
    t.hi[f] = std::max(on_face, off);
  }
  return t;
}

// The pair's contact allowance and the reach that scales an axis' rounding.
struct PairTolerance {
  double slack;
  double reach;
};

PairTolerance ToleranceOf(const TetAxes& a, const TetAxes& b) {
  const double magnitude = std::max(a.magnitude, b.magnitude);
  // The projections are of absolute coordinates: they round with the coordinates' magnitude,
  // which 8 eps M covers for the points and the reach (sqrt(3) M) for the axis' own rounding.
  return {kRelativeSlack * std::max(a.longest, b.longest) + 8.0 * kEps * magnitude,
          1.7320508075688772 * magnitude};
}

// How far the projections of `a` (its interval [a_lo, a_hi]) and of b's corners on axis n
// overlap, or -1 when n separates them: by no more than the slack (contact) plus the axis'
// rounding (n's components carry about eps |u| |v| each, which moves a projection by that times
// the reach: an axis from nearly parallel edges is too rough to claim an overlap along it).
double AxisOverlap(const Vec3& n, double n_len, double n_scale, double a_lo, double a_hi,
                   const std::array<Vec3, 4>& b, const PairTolerance& tol) {
  double b_lo = Dot(n, b[0]), b_hi = b_lo;
  for (int i = 1; i < 4; ++i) {
    const double x = Dot(n, b[i]);
    b_lo = std::min(b_lo, x);
    b_hi = std::max(b_hi, x);
  }
  const double overlap = std::min(a_hi, b_hi) - std::max(a_lo, b_lo);
  if (overlap <= tol.slack * n_len + 16.0 * kEps * n_scale * tol.reach) return -1.0;
  return overlap / n_len;
}

// Phase 1 of the pair test: a's face normals against b's corners. Neighbours that share a
// corner or an edge are mostly told apart here, on data computed once per tet. Returns the
// least overlap, or -1 if one of them separates.
double FaceAxesOverlap(const TetAxes& a, const TetAxes& b, const PairTolerance& tol) {
  double depth = std::numeric_limits<double>::infinity();
  for (int f = 0; f < 4; ++f) {
    const double o = AxisOverlap(a.n[f], a.n_len[f], a.n_scale[f], a.lo[f], a.hi[f], b.p, tol);
    if (o < 0.0) return -1.0;
    depth = std::min(depth, o);
  }
  return depth;
}

// The rest of the pair test: the 36 cross products of an edge of each.
double EdgeAxesOverlap(const TetAxes& a, const TetAxes& b, const PairTolerance& tol) {
  double depth = std::numeric_limits<double>::infinity();
  for (const auto& [a0, a1] : kTetEdges) {
    const Vec3 u = Sub(a.p[a1], a.p[a0]);
    const double u_len = Norm(u);
    for (const auto& [b0, b1] : kTetEdges) {
      const Vec3 v = Sub(b.p[b1], b.p[b0]);
      const Vec3 n = Cross(u, v);
      const double n_len = Norm(n), scale = u_len * Norm(v);
      // Parallel edges (a tet against itself or a copy) give no axis: their cross product is
      // rounding noise, and a separating plane, if any, is among the other axes.
      if (!(n_len > 1e-9 * scale)) continue;
      double a_lo = Dot(n, a.p[0]), a_hi = a_lo;
      for (int i = 1; i < 4; ++i) {
        const double x = Dot(n, a.p[i]);
        a_lo = std::min(a_lo, x);
        a_hi = std::max(a_hi, x);
      }
      const double o = AxisOverlap(n, n_len, scale, a_lo, a_hi, b.p, tol);
      if (o < 0.0) return -1.0;
      depth = std::min(depth, o);
    }
  }
  return depth;
}

double PairDepth(const TetAxes& a, const TetAxes& b) {
  const PairTolerance tol = ToleranceOf(a, b);
  const double da = FaceAxesOverlap(a, b, tol);
  if (da < 0.0) return 0.0;
  const double db = FaceAxesOverlap(b, a, tol);
  if (db < 0.0) return 0.0;
  const double de = EdgeAxesOverlap(a, b, tol);
  if (de < 0.0) return 0.0;
  return std::min({da, db, de});
}

// A static bounding-box tree: the boxes in Morton order of their centres (one sort), split at
// the middle of that order down to leaves of up to four, each node's box the union of its
// children's. Building costs one sort; the shape only affects speed, as a query visits every
// box that meets.
class BoxTree {
 public:
  explicit BoxTree(std::vector<Box> boxes) : boxes_(std::move(boxes)) {
    const size_t n = boxes_.size();
    if (n == 0) return;
    Vec3 lo = Centre(boxes_[0]), hi = lo;
    for (const Box& b : boxes_) {
      const Vec3 c = Centre(b);
      for (int a = 0; a < 3; ++a) {
        lo[a] = std::min(lo[a], c[a]);
        hi[a] = std::max(hi[a], c[a]);
      }
    }
    std::vector<std::pair<uint64_t, uint32_t>> keyed(n);
    for (size_t i = 0; i < n; ++i) {
      const Vec3 c = Centre(boxes_[i]);
      uint64_t code = 0;
      for (int a = 0; a < 3; ++a) {
        const double span = hi[a] - lo[a];
        const double x = span > 0.0 ? (c[a] - lo[a]) / span * 2097151.0 : 0.0;
        // NaN or out of range (coordinates near the double range) clamp; order only.
        const uint64_t q = x >= 0.0 ? static_cast<uint64_t>(std::min(x, 2097151.0)) : 0;
        code |= Spread(q) << a;
      }
      keyed[i] = {code, static_cast<uint32_t>(i)};
    }
    std::sort(keyed.begin(), keyed.end());
    order_.resize(n);
    for (size_t i = 0; i < n; ++i) order_[i] = keyed[i].second;
    nodes_.reserve(2 * n / kLeafSize + 2);
    Build(0, static_cast<uint32_t>(n));
  }

  // Calls visit(i) for every box i that meets `query`.
  template <typename Visit>
  void ForEachMeeting(const Box& query, Visit visit) const {
    if (nodes_.empty()) return;
    // Median splits keep the depth within log2(n) + 1, and a depth-first walk holds at most
    // one pending node per level.
    uint32_t stack[72];
    int top = 0;
    stack[top++] = 0;
    while (top > 0) {
      const Node& node = nodes_[stack[--top]];
      if (!Meet(node.box, query)) continue;
      if (node.right == 0) {
        for (uint32_t k = node.first; k < node.end; ++k) {
          if (Meet(boxes_[order_[k]], query)) visit(order_[k]);
        }
      } else {
        stack[top++] = node.first;
        stack[top++] = node.right;
      }
    }
  }

 private:
  struct Node {
    Box box;
    // A leaf (right == 0) holds order_[first, end); an inner node's children are nodes_[first]
    // and nodes_[right].
    uint32_t first = 0;
    uint32_t end = 0;
    uint32_t right = 0;
  };
  static constexpr uint32_t kLeafSize = 4;

  // The node for order_[begin, end): returns its index.
  uint32_t Build(uint32_t begin, uint32_t end) {
    const uint32_t index = static_cast<uint32_t>(nodes_.size());
    nodes_.emplace_back();
    if (end - begin <= kLeafSize) {
      Box box = boxes_[order_[begin]];
      for (uint32_t k = begin + 1; k < end; ++k) box = Union(box, boxes_[order_[k]]);
      nodes_[index] = {box, begin, end, 0};
      return index;
    }
    const uint32_t mid = begin + (end - begin) / 2;
    const uint32_t left = Build(begin, mid);
    const uint32_t right = Build(mid, end);
    nodes_[index] = {Union(nodes_[left].box, nodes_[right].box), left, 0, right};
    return index;
  }

  static Box Union(const Box& x, const Box& y) {
    Box u;
    for (int a = 0; a < 3; ++a) {
      u.lo[a] = std::min(x.lo[a], y.lo[a]);
      u.hi[a] = std::max(x.hi[a], y.hi[a]);
    }
    return u;
  }

  // 21 bits spread to every third bit.
  static uint64_t Spread(uint64_t x) {
    x &= 0x1fffff;
    x = (x | x << 32) & 0x1f00000000ffffull;
    x = (x | x << 16) & 0x1f0000ff0000ffull;
    x = (x | x << 8) & 0x100f00f00f00f00full;
    x = (x | x << 4) & 0x10c30c30c30c30c3ull;
    x = (x | x << 2) & 0x1249249249249249ull;
    return x;
  }

  static Vec3 Centre(const Box& b) {
    return {0.5 * (b.lo[0] + b.hi[0]), 0.5 * (b.lo[1] + b.hi[1]), 0.5 * (b.lo[2] + b.hi[2])};
  }

  std::vector<Box> boxes_;
  std::vector<uint32_t> order_;
  std::vector<Node> nodes_;
};

// A uniform grid over the boundary faces' boxes, each cell listing the faces whose box touches
// it (compressed rows). It is also the filter that passes over the tets away from the boundary:
// a tet whose box touches only empty cells costs a few lookups, on cells that neighbouring tets
// share in cache.
// Why this index, measured on the check alone (bench/core_bench, 1 thread; the checks 1-4 take
// 12 ms, 384 ms and 14 ms of these): a 60^3-cell FiveTetMesh (1.08 M tets, 43 k boundary
// faces) 97 ms; 250 k separate tets (1 M boundary faces) 1080 ms; a 40^3-cell mesh graded over
// a factor 2^13 (320 k tets) 668 ms, where the grid's cells, sized to the average face, crowd
// the finest faces. A Morton-ordered box tree gave 183 / 1744 / 390 ms, a median-split tree
// with a coarse occupancy filter 172 / 2099 / 111 ms, a hash grid with one level per power of
// two of face size (check 1's) 205 / 1945 / 582 ms: the tree walks cost more than the grid's
// lookups on ordinary meshes, which matter most.
class FaceCellGrid {
 public:
  // Faces whose box spans more cells than this are kept in a tree of their own that every
  // query walks (faces far larger than the average: a graded boundary).
  static constexpr int64_t kMaxCellsPerFace = 64;
  // Tets whose box spans more cells than this are looked up in a tree over all faces, built
  // the first time one comes (a coarse tet beside a finely meshed boundary).
  static constexpr int64_t kMaxCellsPerQuery = 512;

  explicit FaceCellGrid(const std::vector<Box>& boxes) : boxes_(boxes) {
    lo_ = boxes[0].lo;
    Vec3 hi = boxes[0].hi;
    double widths = 0.0;
    for (const Box& b : boxes) {
      for (int a = 0; a < 3; ++a) {
        lo_[a] = std::min(lo_[a], b.lo[a]);
        hi[a] = std::max(hi[a], b.hi[a]);
      }
      widths += std::max({b.hi[0] - b.lo[0], b.hi[1] - b.lo[1], b.hi[2] - b.lo[2]});
    }
    // Cells about as wide as a face on average, at most 2^21 of them (8 MB of offsets) and at
    // most about four per face, so the grid never outweighs the boundary.
    const double extent = std::max({hi[0] - lo_[0], hi[1] - lo_[1], hi[2] - lo_[2]});
    const double budget =
        std::min<double>(static_cast<double>(int64_t{1} << 21), 4.0 * boxes.size() + 8.0);
    h_ = std::max(widths / static_cast<double>(boxes.size()), extent / 4096.0);
    for (;;) {
      double cells = 1.0;
      for (int a = 0; a < 3; ++a) cells *= std::floor((hi[a] - lo_[a]) / h_) + 1.0;
      if (cells <= budget || !(h_ > 0.0)) break;
      h_ *= 1.25;
    }
    if (!(h_ > 0.0)) h_ = 1.0;
    for (int a = 0; a < 3; ++a) {
      dims_[a] = static_cast<int64_t>(std::floor((hi[a] - lo_[a]) / h_)) + 1;
    }
    const int64_t num_cells = dims_[0] * dims_[1] * dims_[2];
    start_.assign(static_cast<size_t>(num_cells + 1), 0);
    const int64_t n = static_cast<int64_t>(boxes.size());
    low_cell_.resize(boxes.size());
    std::vector<Box> big_boxes;
    for (int64_t f = 0; f < n; ++f) {
      const Range r = RangeOf(boxes[f]);
      for (int a = 0; a < 3; ++a) low_cell_[f][a] = static_cast<int32_t>(r.lo[a]);
      if (r.cells() > kMaxCellsPerFace) {
        big_.push_back(static_cast<uint32_t>(f));
        big_boxes.push_back(boxes[f]);
        continue;
      }
      r.ForEach(dims_, [&](int64_t c) { ++start_[c + 1]; });
    }
    big_tree_ = std::make_unique<BoxTree>(std::move(big_boxes));
    for (int64_t c = 0; c < num_cells; ++c) start_[c + 1] += start_[c];
    faces_.resize(static_cast<size_t>(start_[num_cells]));
    std::vector<int64_t> fill(start_.begin(), start_.end() - 1);
    for (int64_t f = 0; f < n; ++f) {
      const Range r = RangeOf(boxes[f]);
      if (r.cells() > kMaxCellsPerFace) continue;
      r.ForEach(dims_, [&](int64_t c) { faces_[fill[c]++] = static_cast<uint32_t>(f); });
    }
  }

  // Calls visit(f) once for every face f whose box meets `query`.
  template <typename Visit>
  void ForEachMeeting(const Box& query, Visit visit) const {
    for (int a = 0; a < 3; ++a) {
      if (query.hi[a] < lo_[a] || query.lo[a] > lo_[a] + h_ * static_cast<double>(dims_[a])) {
        return;
      }
    }
    const Range q = RangeOf(query);
    if (q.cells() > kMaxCellsPerQuery) {
      // A tet far larger than the faces: one walk down a tree over all of them instead.
      std::call_once(all_tree_once_, [&] { all_tree_ = std::make_unique<BoxTree>(boxes_); });
      all_tree_->ForEachMeeting(query, visit);
      return;
    }
    big_tree_->ForEachMeeting(query, [&](uint32_t b) { visit(big_[b]); });
    q.ForEach(dims_, [&](int64_t c) {
      for (int64_t e = start_[c]; e < start_[c + 1]; ++e) {
        const uint32_t f = faces_[e];
        if (!Meet(boxes_[f], query)) continue;
        // A face in several of the query's cells is visited from the first of them only: the
        // cell at the larger of the two ranges' low corners.
        const std::array<int32_t, 3>& low = low_cell_[f];
        int64_t first = 0;
        for (int a = 2; a >= 0; --a) first = first * dims_[a] + std::max<int64_t>(q.lo[a], low[a]);
        if (first == c) visit(f);
      }
    });
  }

 private:
  struct Range {
    std::array<int64_t, 3> lo, hi;  // inclusive
    int64_t cells() const {
      return (hi[0] - lo[0] + 1) * (hi[1] - lo[1] + 1) * (hi[2] - lo[2] + 1);
    }
    template <typename Body>
    void ForEach(const std::array<int64_t, 3>& dims, Body body) const {
      for (int64_t k = lo[2]; k <= hi[2]; ++k) {
        for (int64_t j = lo[1]; j <= hi[1]; ++j) {
          for (int64_t i = lo[0]; i <= hi[0]; ++i) body((k * dims[1] + j) * dims[0] + i);
        }
      }
    }
  };

  Range RangeOf(const Box& b) const {
    Range r;
    for (int a = 0; a < 3; ++a) {
      r.lo[a] = Cell(b.lo[a], a);
      r.hi[a] = std::max(r.lo[a], Cell(b.hi[a], a));
    }
    return r;
  }
  int64_t Cell(double x, int a) const {
    const double c = std::floor((x - lo_[a]) / h_);
    if (!(c >= 0.0)) return 0;  // also NaN
    return std::min(static_cast<int64_t>(std::min(c, 0x1p50)), dims_[a] - 1);
  }

  const std::vector<Box>& boxes_;
  Vec3 lo_{};
  double h_ = 1.0;
  std::array<int64_t, 3> dims_{1, 1, 1};
  std::vector<int64_t> start_;  // cell c lists faces_[start_[c], start_[c + 1])
  std::vector<uint32_t> faces_;
  std::vector<uint32_t> big_;                     // the faces in big_tree_, by their index there
  std::vector<std::array<int32_t, 3>> low_cell_;  // each face's first cell on each axis
  std::unique_ptr<BoxTree> big_tree_;
  mutable std::once_flag all_tree_once_;
  mutable std::unique_ptr<BoxTree> all_tree_;
};

// A boundary face's plane, oriented towards its own tet: s(p) = n . p - offset is > 0 on that
// tet's side. `tolerance` is how far in s a point may be and still count as on the plane.
struct FacePlane {
  Vec3 n;
  double offset;
  double tolerance;
};

FacePlane PlaneOf(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& inside) {
  const Vec3 u = Sub(b, a), v = Sub(c, a);
  FacePlane plane;
  plane.n = Cross(u, v);
  plane.offset = Dot(plane.n, a);
  if (Dot(plane.n, inside) - plane.offset < 0.0) {
    plane.n = {-plane.n[0], -plane.n[1], -plane.n[2]};
    plane.offset = -plane.offset;
  }
  double longest = std::max({Norm(u), Norm(v), Norm(Sub(c, b))}), magnitude = 0.0;
  for (const Vec3* p : {&a, &b, &c}) {
    magnitude = std::max({magnitude, std::abs((*p)[0]), std::abs((*p)[1]), std::abs((*p)[2])});
  }
  // As the pair test's slack and axis rounding, for this one axis.
  plane.tolerance = (kRelativeSlack * longest + 8.0 * kEps * magnitude) * Norm(plane.n) +
                    16.0 * kEps * Norm(u) * Norm(v) * 1.7320508075688772 * magnitude;
  return plane;
}

// Whether tet `p` can be the other tet of an overlap witnessed at this face (tet_overlap.h):
// its closure must hold a patch of the face of positive area with its interior on the face's
// own side, so it either crosses the plane or lies on that side with a face in the plane. Tets
// that touch the plane from the inside at a corner or an edge (every neighbour of a convex
// boundary) or lie outside are passed over on four dot products.
// `in_plane` receives the corners of p on the plane when p lies on the inner side with a face
// in it (then 3 of them), else nothing.
bool MayCoverFace(const FacePlane& plane, const std::array<Vec3, 4>& p,
                  std::array<const Vec3*, 3>* in_plane) {
  int inner = 0, outer = 0, on = 0;
  for (const Vec3& q : p) {
    const double s = Dot(plane.n, q) - plane.offset;
    if (s > plane.tolerance) {
      ++inner;
    } else if (s < -plane.tolerance) {
      ++outer;
    } else if (on < 3) {
      (*in_plane)[on++] = &q;
    }
  }
  if (inner == 0) return false;
  if (outer > 0) {
    (*in_plane)[0] = nullptr;
    return true;
  }
  if (on < 3) return false;
  return true;
}

// Whether two triangles in one plane (normal n) overlap in more than their outlines: no edge
// normal in the plane separates them by more than the plane's tolerance allows. On the
// triangle sharing an edge with the face on the other side of it (every coplanar neighbour
// on a flat boundary), that edge's normal separates them.
bool CoplanarOverlap(const FacePlane& plane, const std::array<const Vec3*, 3>& f,
                     const std::array<const Vec3*, 3>& g) {
  const double n_len = Norm(plane.n);
  for (const auto* tri : {&f, &g}) {
    for (int e = 0; e < 3; ++e) {
      const Vec3 edge = Sub(*(*tri)[(e + 1) % 3], *(*tri)[e]);
      const Vec3 m = Cross(plane.n, edge);
      double f_lo = Dot(m, *f[0]), f_hi = f_lo, g_lo = Dot(m, *g[0]), g_hi = g_lo;
      for (int i = 1; i < 3; ++i) {
        const double x = Dot(m, *f[i]), y = Dot(m, *g[i]);
        f_lo = std::min(f_lo, x);
        f_hi = std::max(f_hi, x);
        g_lo = std::min(g_lo, y);
        g_hi = std::max(g_hi, y);
      }
      // |m| = |n| |edge|: the plane's tolerance (a length times |n|) times |edge|.
      if (std::min(f_hi, g_hi) - std::max(f_lo, g_lo) <=
          plane.tolerance * Norm(edge) * 2.0 + 16.0 * kEps * n_len * Norm(edge) * Norm(*f[0])) {
        return false;
      }
    }
  }
  return true;
}

// An overlapping pair, smaller tet first, with the owner whose face the message names.
struct Overlap {
  int64_t first = 0;
  int64_t second = 0;
  int64_t face = 0;  // index into the faces list: the face the overlap was found at
  double depth = 0.0;
};

}  // namespace

double OverlapDepth(const std::array<Vec3, 4>& a, const std::array<Vec3, 4>& b) {
  return PairDepth(AxesOf(a), AxesOf(b));
}

absl::Status CheckOverlaps(const std::vector<Vec3>& points, const std::vector<Tet>& tets,
                           const std::vector<OwnedFace>& faces) {
  if (faces.empty()) return absl::OkStatus();
  const int64_t num_faces = static_cast<int64_t>(faces.size());
  const int64_t num_tets = static_cast<int64_t>(tets.size());
  std::vector<Box> boxes(faces.size());
  std::vector<FacePlane> planes(faces.size());
  ForEachBlock(num_faces, [&](int64_t, int64_t begin, int64_t end) {
    for (int64_t f = begin; f < end; ++f) {
      const BoundaryFace& face = faces[f].face;
      const Tet& own = tets[faces[f].tet];
      uint32_t inside = own[0];
      for (uint32_t v : own) {
        if (v != face[0] && v != face[1] && v != face[2]) inside = v;
      }
      const Vec3 &a = points[face[0]], &b = points[face[1]], &c = points[face[2]];
      planes[f] = PlaneOf(a, b, c, points[inside]);
      // Grown by the plane's tolerance in length and then some, so no tet the plane test could
      // keep is missed by the box test.
      const double grow = 2.0 * planes[f].tolerance / Norm(planes[f].n) +
                          64.0 * kEps *
                              std::max({std::abs(a[0]), std::abs(a[1]), std::abs(a[2]),
                                        std::abs(b[0]), std::abs(b[1]), std::abs(b[2]),
                                        std::abs(c[0]), std::abs(c[1]), std::abs(c[2])});
      Box box{a, a};
      for (const Vec3* q : {&b, &c}) {
        for (int i = 0; i < 3; ++i) {
          box.lo[i] = std::min(box.lo[i], (*q)[i]);
          box.hi[i] = std::max(box.hi[i], (*q)[i]);
        }
      }
      for (int i = 0; i < 3; ++i) {
        box.lo[i] -= grow;
        box.hi[i] += grow;
      }
      boxes[f] = box;
    }
  });
  const FaceCellGrid grid(boxes);
  std::vector<std::vector<Overlap>> found(BlockCount(num_tets));
  ForEachBlock(num_tets, [&](int64_t block, int64_t begin, int64_t end) {
    for (int64_t t = begin; t < end; ++t) {
      const std::array<Vec3, 4> p = Corners(points, tets[t]);
      TetAxes mine;
      bool have_mine = false;
      grid.ForEachMeeting(BoxOf(p, 0.0), [&](uint32_t f) {
        const int64_t owner = faces[f].tet;
        if (owner == t) return;
        std::array<const Vec3*, 3> in_plane{};
        if (!MayCoverFace(planes[f], p, &in_plane)) return;
        if (in_plane[0] != nullptr) {
          const BoundaryFace& face = faces[f].face;
          if (!CoplanarOverlap(planes[f], {&points[face[0]], &points[face[1]], &points[face[2]]},
                               in_plane)) {
            return;
          }
        }
        if (!have_mine) {
          mine = AxesOf(p);
          have_mine = true;
        }
        const double depth = PairDepth(AxesOf(Corners(points, tets[owner])), mine);
        if (depth > 0.0) {
          found[block].push_back({std::min(t, owner), std::max(t, owner), f, depth});
        }
      });
    }
  });
  const Overlap* first = nullptr;
  for (const std::vector<Overlap>& f : found) {
    for (const Overlap& o : f) {
      if (first == nullptr || std::tie(o.first, o.second, o.face) <
                                  std::tie(first->first, first->second, first->face)) {
        first = &o;
      }
    }
  }
  if (first == nullptr) return absl::OkStatus();
  const OwnedFace& owner = faces[first->face];
  const BoundaryFace& f = owner.face;
  return absl::InvalidArgumentError(absl::StrCat(
      "mesh is not conformal: mesh.tets[", first->first, "] and mesh.tets[", first->second,
      "] overlap (their interiors intersect, ", absl::StrFormat("%.3g", first->depth),
      " deep at the least); mesh.tets[", owner.tet, "] has boundary face (", f[0], ", ", f[1], ", ",
      f[2],
      "), so two parts of the mesh cover the same space (a region triangulated differently on "
      "its two sides, a mesh inside another, or a boundary folded into the mesh)"));
}

}  // namespace tet_overlap_internal

double TetOverlapDepth(const std::array<Vec3, 4>& a, const std::array<Vec3, 4>& b) {
  return tet_overlap_internal::OverlapDepth(a, b);
}

absl::Status CheckNoOverlappingTets(const std::vector<Vec3>& points, const std::vector<Tet>& tets,
                                    const std::vector<OwnedFace>& faces) {
  return tet_overlap_internal::CheckOverlaps(points, tets, faces);
}

}  // namespace tetrefine
