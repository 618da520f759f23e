#include "core/tet_overlap.h"

#include <algorithm>
#include <array>
#include <bit>
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
#include "core/vec3_ops.h"

namespace tetrefine {
// A named namespace, not an anonymous one: a unity build compiles this file together with the
// other core files, whose file-local names (Box, Overlap, ...) must not meet these.
namespace tet_overlap_internal {
namespace {

constexpr double kEps = std::numeric_limits<double>::epsilon();
// Contact within 1e-10 of the pair's size is not an overlap: well above the rounding of the
// coordinates (check 1 takes 1e-13 for a vertex on a face) and well below any overlap a mesh
// generator or a mistaken merge produces.
constexpr double kRelativeSlack = 1e-10;

struct Box {
  Vec3 lo, hi;
};

// The box of `points`, grown by `grow` on every side.
template <size_t N>
Box BoxOf(const std::array<const Vec3*, N>& points, double grow) {
  Box b{*points[0], *points[0]};
  for (size_t i = 1; i < N; ++i) {
    for (int a = 0; a < 3; ++a) {
      b.lo[a] = std::min(b.lo[a], (*points[i])[a]);
      b.hi[a] = std::max(b.hi[a], (*points[i])[a]);
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

// A static bounding-box tree (median splits along the widest spread of the boxes' centres, up
// to four boxes a leaf). Its shape only affects speed: a query visits every box that meets.
class BoxTree {
 public:
  explicit BoxTree(std::vector<Box> boxes) : boxes_(std::move(boxes)) {
    order_.resize(boxes_.size());
    std::iota(order_.begin(), order_.end(), uint32_t{0});
    nodes_.reserve(2 * boxes_.size() / kLeafSize + 1);
    if (!order_.empty()) Build(0, static_cast<uint32_t>(order_.size()));
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
    Box box = boxes_[order_[begin]];
    Box centres{Centre(box), Centre(box)};
    for (uint32_t k = begin + 1; k < end; ++k) {
      const Box& b = boxes_[order_[k]];
      const Vec3 c = Centre(b);
      for (int a = 0; a < 3; ++a) {
        box.lo[a] = std::min(box.lo[a], b.lo[a]);
        box.hi[a] = std::max(box.hi[a], b.hi[a]);
        centres.lo[a] = std::min(centres.lo[a], c[a]);
        centres.hi[a] = std::max(centres.hi[a], c[a]);
      }
    }
    nodes_[index].box = box;
    if (end - begin <= kLeafSize) {
      nodes_[index].first = begin;
      nodes_[index].end = end;
      return index;
    }
    int axis = 0;
    for (int a = 1; a < 3; ++a) {
      if (centres.hi[a] - centres.lo[a] > centres.hi[axis] - centres.lo[axis]) axis = a;
    }
    const uint32_t mid = begin + (end - begin) / 2;
    std::nth_element(order_.begin() + begin, order_.begin() + mid, order_.begin() + end,
                     [&](uint32_t x, uint32_t y) {
                       const double cx = Centre(boxes_[x])[axis], cy = Centre(boxes_[y])[axis];
                       return cx < cy || (cx == cy && x < y);
                     });
    const uint32_t left = Build(begin, mid);
    const uint32_t right = Build(mid, end);
    nodes_[index].first = left;
    nodes_[index].right = right;
    return index;
  }

  static Vec3 Centre(const Box& b) {
    return {0.5 * (b.lo[0] + b.hi[0]), 0.5 * (b.lo[1] + b.hi[1]), 0.5 * (b.lo[2] + b.hi[2])};
  }

  std::vector<Box> boxes_;
  std::vector<uint32_t> order_;
  std::vector<Node> nodes_;
};

// Which cells of a coarse grid over the boundary faces' boxes some face box touches, with a
// summed-area table so that "does this box touch one" costs eight lookups: most tets of a mesh
// lie away from its boundary and are passed over on it without a walk down the box tree.
class Occupancy {
 public:
  Occupancy(const std::vector<Box>& boxes, int64_t num_tets) {
    lo_ = boxes[0].lo;
    Vec3 hi = boxes[0].hi;
    for (const Box& b : boxes) {
      for (int a = 0; a < 3; ++a) {
        lo_[a] = std::min(lo_[a], b.lo[a]);
        hi[a] = std::max(hi[a], b.hi[a]);
      }
    }
    // About one and a half cells per tet along the widest axis of a cube-like mesh, at most 96:
    // at most 97^3 counters (3.6 MB) to build and sum, a few ms.
    const double extent = std::max({hi[0] - lo_[0], hi[1] - lo_[1], hi[2] - lo_[2]});
    const int cells =
        std::clamp(static_cast<int>(1.5 * std::cbrt(static_cast<double>(num_tets))), 1, 96);
    h_ = extent > 0.0 ? extent / cells : 1.0;
    for (int a = 0; a < 3; ++a) {
      dims_[a] = std::clamp(static_cast<int64_t>((hi[a] - lo_[a]) / h_) + 1, int64_t{1},
                            int64_t{cells} + 1);
    }
    // Box counts per cell as a 3-D difference array, summed along each axis; then a summed-area
    // table of the touched cells, in the same array, one larger along each axis.
    const int64_t nx = dims_[0] + 1, ny = dims_[1] + 1, nz = dims_[2] + 1;
    sum_.assign(static_cast<size_t>(nx * ny * nz), 0);
    auto at = [&](int64_t i, int64_t j, int64_t k) -> int64_t& {
      return sum_[static_cast<size_t>((k * ny + j) * nx + i)];
    };
    for (const Box& b : boxes) {
      int64_t c0[3], c1[3];
      CellRange(b, c0, c1);
      for (int corner = 0; corner < 8; ++corner) {
        const int64_t i = corner & 1 ? c1[0] + 1 : c0[0];
        const int64_t j = corner & 2 ? c1[1] + 1 : c0[1];
        const int64_t k = corner & 4 ? c1[2] + 1 : c0[2];
        at(i, j, k) += std::popcount(static_cast<unsigned>(corner)) % 2 ? -1 : 1;
      }
    }
    for (int64_t k = 0; k < nz; ++k) {
      for (int64_t j = 0; j < ny; ++j) {
        for (int64_t i = 1; i < nx; ++i) at(i, j, k) += at(i - 1, j, k);
      }
    }
    for (int64_t k = 0; k < nz; ++k) {
      for (int64_t j = 1; j < ny; ++j) {
        for (int64_t i = 0; i < nx; ++i) at(i, j, k) += at(i, j - 1, k);
      }
    }
    for (int64_t k = 1; k < nz; ++k) {
      for (int64_t j = 0; j < ny; ++j) {
        for (int64_t i = 0; i < nx; ++i) at(i, j, k) += at(i, j, k - 1);
      }
    }
    // Now at(i, j, k) is the count of cell (i, j, k); turned into 0/1 and summed again, shifted
    // by one, so that at(i, j, k) counts the touched cells below (i, j, k) on every axis.
    for (int64_t k = nz - 1; k >= 0; --k) {
      for (int64_t j = ny - 1; j >= 0; --j) {
        for (int64_t i = nx - 1; i >= 0; --i) {
          const bool inside = i > 0 && j > 0 && k > 0;
          at(i, j, k) = inside && at(i - 1, j - 1, k - 1) > 0 ? 1 : 0;
        }
      }
    }
    for (int axis = 0; axis < 3; ++axis) {
      for (int64_t k = axis == 2 ? 1 : 0; k < nz; ++k) {
        for (int64_t j = axis == 1 ? 1 : 0; j < ny; ++j) {
          for (int64_t i = axis == 0 ? 1 : 0; i < nx; ++i) {
            at(i, j, k) += axis == 0   ? at(i - 1, j, k)
                           : axis == 1 ? at(i, j - 1, k)
                                       : at(i, j, k - 1);
          }
        }
      }
    }
  }

  // Whether `b` touches a cell some face box touches.
  bool Touches(const Box& b) const {
    for (int a = 0; a < 3; ++a) {
      if (b.hi[a] < lo_[a] || b.lo[a] > lo_[a] + h_ * static_cast<double>(dims_[a])) return false;
    }
    int64_t c0[3], c1[3];
    CellRange(b, c0, c1);
    const int64_t nx = dims_[0] + 1, ny = dims_[1] + 1;
    auto at = [&](int64_t i, int64_t j, int64_t k) {
      return sum_[static_cast<size_t>((k * ny + j) * nx + i)];
    };
    const int64_t x0 = c0[0], y0 = c0[1], z0 = c0[2];
    const int64_t x1 = c1[0] + 1, y1 = c1[1] + 1, z1 = c1[2] + 1;
    const int64_t count = at(x1, y1, z1) - at(x0, y1, z1) - at(x1, y0, z1) - at(x1, y1, z0) +
                          at(x0, y0, z1) + at(x0, y1, z0) + at(x1, y0, z0) - at(x0, y0, z0);
    return count > 0;
  }

 private:
  // The cells [c0, c1] (inclusive) a box spans, clamped to the grid.
  void CellRange(const Box& b, int64_t* c0, int64_t* c1) const {
    for (int a = 0; a < 3; ++a) {
      c0[a] = Cell(b.lo[a], a);
      c1[a] = std::max(c0[a], Cell(b.hi[a], a));
    }
  }
  int64_t Cell(double x, int a) const {
    const double c = std::floor((x - lo_[a]) / h_);
    if (!(c >= 0.0)) return 0;  // also NaN
    return std::min(static_cast<int64_t>(std::min(c, 0x1p50)), dims_[a] - 1);
  }

  Vec3 lo_{};
  double h_ = 1.0;
  std::array<int64_t, 3> dims_{1, 1, 1};
  std::vector<int64_t> sum_;
};

// A uniform grid over the boundary faces' boxes, each cell listing the faces whose box touches
// it (compressed rows). It is also the filter that passes over the tets away from the boundary:
// a tet whose box touches only empty cells costs a few lookups, on cells that neighbouring tets
// share in cache.
// Why these indexes, measured on the conformity check's part (bench/core_bench, 1 thread; the
// checks 1-4 alone take 12 ms, 572 ms and 16 ms of these; this VM's run-to-run noise is about
// +-30%): a 60^3-cell FiveTetMesh (1.08 M tets, 43 k boundary faces), 250 k separate tets
// (1 M boundary faces), a 40^3-cell mesh graded over a factor 2^13 (320 k tets):
//   this uniform grid                            97-160 / 1080-1570 / 668 ms
//   a median-split box tree + an occupancy filter   172 / 2099 / 111 ms
//   a Morton-ordered box tree                       183 / 1744 / 390 ms
//   a hash grid, one level per power of two (check 1's)   205 / 1945 / 582 ms
// The grid's lookups beat the trees' walks on ordinary meshes, which matter most; on a graded
// boundary its cells, sized to the average face, crowd with the smallest faces. So the check
// takes the grid where the face sizes are alike and the tree where they are not (SizeSpread).
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
    inv_h_ = 1.0 / h_;
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
    occupied_.assign(static_cast<size_t>((num_cells + 63) / 64), 0);
    block_occupied_.assign(occupied_.size(), 0);
    for (int64_t c = 0; c < num_cells; ++c) {
      if (start_[c + 1] > 0) {
        occupied_[c >> 6] |= uint64_t{1} << (c & 63);
        MarkBlocksHolding(c);
      }
      start_[c + 1] += start_[c];
    }
    faces_.resize(static_cast<size_t>(start_[num_cells]));
    std::vector<int64_t> fill(start_.begin(), start_.end() - 1);
    for (int64_t f = 0; f < n; ++f) {
      const Range r = RangeOf(boxes[f]);
      if (r.cells() > kMaxCellsPerFace) continue;
      r.ForEach(dims_, [&](int64_t c) { faces_[fill[c]++] = static_cast<uint32_t>(f); });
    }
  }

  // Each point's cell on each axis, as RangeOf bins a coordinate. Cell is monotone, so the
  // range of a box around points is the range of their cells: a tet's range comes from its
  // corners' cells, binned once per point instead of once per tet that has the point.
  std::vector<std::array<int32_t, 3>> PointCells(const std::vector<Vec3>& points) const {
    std::vector<std::array<int32_t, 3>> cells(points.size());
    ForEachBlock(static_cast<int64_t>(points.size()), [&](int64_t, int64_t begin, int64_t end) {
      for (int64_t i = begin; i < end; ++i) {
        for (int a = 0; a < 3; ++a) cells[i][a] = static_cast<int32_t>(Cell(points[i][a], a));
      }
    });
    return cells;
  }

  // False when ForEachMeeting would visit no face for a query whose range is [lo, hi]: at most
  // two cells on each axis, none of them listing a face, and no face in the big tree. Most tets
  // of a mesh are such queries, answered here from one bit.
  bool MayMeet(const std::array<int32_t, 3>& lo, const std::array<int32_t, 3>& hi) const {
    if (!big_.empty()) return true;
    for (int a = 0; a < 3; ++a) {
      if (hi[a] - lo[a] > 1) return true;
    }
    const int64_t c = (int64_t{lo[2]} * dims_[1] + lo[1]) * dims_[0] + lo[0];
    return (block_occupied_[c >> 6] >> (c & 63) & 1) != 0;
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
      if ((occupied_[c >> 6] >> (c & 63) & 1) == 0) return;
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

  // Sets the bit of every cell whose block of 2 x 2 x 2 cells (itself and its upper
  // neighbours) holds cell c.
  void MarkBlocksHolding(int64_t c) {
    const int64_t i = c % dims_[0], j = c / dims_[0] % dims_[1], k = c / (dims_[0] * dims_[1]);
    for (int64_t dk = 0; dk <= std::min<int64_t>(k, 1); ++dk) {
      for (int64_t dj = 0; dj <= std::min<int64_t>(j, 1); ++dj) {
        for (int64_t di = 0; di <= std::min<int64_t>(i, 1); ++di) {
          const int64_t b = ((k - dk) * dims_[1] + (j - dj)) * dims_[0] + (i - di);
          block_occupied_[b >> 6] |= uint64_t{1} << (b & 63);
        }
      }
    }
  }

  Range RangeOf(const Box& b) const {
    Range r;
    for (int a = 0; a < 3; ++a) {
      r.lo[a] = Cell(b.lo[a], a);
      r.hi[a] = std::max(r.lo[a], Cell(b.hi[a], a));
    }
    return r;
  }
  // Monotone in x, so boxes that meet get ranges that share a cell; faces and queries are binned
  // by this same function.
  int64_t Cell(double x, int a) const {
    const double c = std::floor((x - lo_[a]) * inv_h_);
    if (!(c >= 0.0)) return 0;  // also NaN
    return std::min(static_cast<int64_t>(std::min(c, 0x1p50)), dims_[a] - 1);
  }

  const std::vector<Box>& boxes_;
  Vec3 lo_{};
  double h_ = 1.0;
  double inv_h_ = 1.0;
  std::array<int64_t, 3> dims_{1, 1, 1};
  std::vector<int64_t> start_;  // cell c lists faces_[start_[c], start_[c + 1])
  // Bit c set when cell c lists a face: most tets lie where no boundary face is, and this
  // answers for them from 256 KB (at most 2^21 cells) instead of start_'s 16 MB.
  std::vector<uint64_t> occupied_;
  // Bit c set when a cell of c's block (MarkBlocksHolding) lists a face.
  std::vector<uint64_t> block_occupied_;
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

// The 90th percentile of the boxes' widths over the 10th (1 for a single box).
double SizeSpread(const std::vector<Box>& boxes) {
  std::vector<double> widths(boxes.size());
  for (size_t f = 0; f < boxes.size(); ++f) {
    const Box& b = boxes[f];
    widths[f] = std::max({b.hi[0] - b.lo[0], b.hi[1] - b.lo[1], b.hi[2] - b.lo[2]});
  }
  const size_t low = widths.size() / 10, high = widths.size() - 1 - widths.size() / 10;
  std::nth_element(widths.begin(), widths.begin() + low, widths.end());
  const double small = widths[low];
  std::nth_element(widths.begin(), widths.begin() + high, widths.end());
  const double large = widths[high];
  return small > 0.0 ? large / small : (large > 0.0 ? 1e300 : 1.0);
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
  // A face's plane divides by its normal's length, whose square underflows for faces below
  // about 1e-77 across: NaN boxes then reached the grid's float-to-int casts (undefined; seen
  // by UBSan on a mesh scaled by 1e-80, 2026-11-28). 1e-30 world units is far below any mesh
  // of a scan (millimetres or metres) and far above that.
  constexpr double kMinFaceSize = 1e-30;
  if (const int64_t tiny = FirstIndexWhere(
          num_faces,
          [&](int64_t f) {
            const BoundaryFace& face = faces[f].face;
            const Vec3 &a = points[face[0]], &b = points[face[1]], &c = points[face[2]];
            return !(std::max({Norm2(Sub(b, a)), Norm2(Sub(c, a)), Norm2(Sub(c, b))}) >=
                     kMinFaceSize * kMinFaceSize);
          });
      tiny < num_faces) {
    const BoundaryFace& f = faces[tiny].face;
    return absl::InvalidArgumentError(absl::StrCat(
        "mesh.tets[", faces[tiny].tet, "] has boundary face (", f[0], ", ", f[1], ", ", f[2],
        ") whose edges are all shorter than 1e-30: too small for tetrefine's geometry to measure "
        "(scale the mesh to millimetres or metres)"));
  }
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
      boxes[f] = BoxOf(std::array<const Vec3*, 3>{&a, &b, &c}, grow);
    }
  });
  std::vector<std::vector<Overlap>> found(BlockCount(num_tets));
  // The box test's pairs are few per tet on a mesh (tens near a boundary), but a valid mesh can
  // make them quadratic: 20,000 slivers around one edge, whose boxes all meet, took 6 s here and
  // 60,000 took a minute (an outside review, 2026-11-28), a way for one request to hold a
  // server's core. Past kMaxCrowdedPairsPerItem per tet on average (and a floor for small
  // meshes), the mesh is refused (CrowdedPairBudget).
  CrowdedPairBudget pairs(num_tets);
  // Every tet against the faces `index` finds for its box; `may_meet` (from the tet) and
  // `near` (from its box) pass over the tets that cannot meet any.
  auto scan = [&](const auto& index, const auto& may_meet, const auto& near) {
    ForEachBlock(num_tets, [&](int64_t block, int64_t begin, int64_t end) {
      int64_t mine_pairs = 0;
      for (int64_t t = begin; t < end; ++t) {
        if (!pairs.Flush(mine_pairs)) return;
        if (!may_meet(tets[t])) continue;
        const std::array<Vec3, 4> p = Corners(points, tets[t]);
        const Box box = BoxOf(std::array<const Vec3*, 4>{&p[0], &p[1], &p[2], &p[3]}, 0.0);
        if (!near(box)) continue;
        TetAxes mine;
        bool have_mine = false;
        index.ForEachMeeting(box, [&](uint32_t f) {
          ++mine_pairs;
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
      pairs.Finish(mine_pairs);
    });
  };
  // The index, by the spread of face sizes: the uniform grid where they are alike, the tree
  // where they span more than a factor 16 between the 10th and 90th percentile (a graded
  // boundary, whose smallest faces would crowd the grid's cells). Measured in FaceCellGrid's
  // comment.
  if (SizeSpread(boxes) <= 16.0) {
    // Most tets are passed over from their corners' cells. bench/core_bench BM_Validation
    // part 1 (1.08 M tets of a block mesh, 43 k boundary faces, one thread), 2026-11-28,
    // interleaved with the commit before: 109-112 -> 80 ms; BM_ValidationHard unchanged.
    const FaceCellGrid grid(boxes);
    const std::vector<std::array<int32_t, 3>> cells = grid.PointCells(points);
    scan(
        grid,
        [&](const Tet& tet) {
          std::array<int32_t, 3> lo = cells[tet[0]], hi = cells[tet[0]];
          for (int c = 1; c < 4; ++c) {
            for (int a = 0; a < 3; ++a) {
              lo[a] = std::min(lo[a], cells[tet[c]][a]);
              hi[a] = std::max(hi[a], cells[tet[c]][a]);
            }
          }
          return grid.MayMeet(lo, hi);
        },
        [](const Box&) { return true; });
  } else {
    const Occupancy occupancy(boxes, num_tets);
    const BoxTree tree(boxes);
    scan(
        tree, [](const Tet&) { return true; },
        [&](const Box& box) { return occupancy.Touches(box); });
  }
  if (pairs.Exceeded()) {
    return CrowdedMeshError(tets, "tet and a boundary face meet within their bounding boxes",
                            pairs.max());
  }
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
  // The depth divides by face normals' lengths, whose squares underflow for tets below about
  // 1e-77 across: the overlap stands, the number does not (a sweep saw "inf deep", 2026-11-28).
  const std::string depth = std::isfinite(first->depth)
                                ? absl::StrFormat(", %.3g deep at the least", first->depth)
                                : std::string();
  return absl::InvalidArgumentError(absl::StrCat(
      "mesh is not conformal: mesh.tets[", first->first, "] and mesh.tets[", first->second,
      "] overlap (their interiors intersect", depth, "); mesh.tets[", owner.tet,
      "] has boundary face (", f[0], ", ", f[1], ", ", f[2],
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

// Off the normal path: its cost does not matter.
absl::Status CrowdedMeshError(const std::vector<Tet>& tets, const std::string& pair,
                              int64_t max_pairs) {
  std::vector<uint64_t> edges;
  edges.reserve(tets.size() * 6);
  for (const Tet& t : tets) {
    for (int a = 0; a < 4; ++a) {
      for (int b = a + 1; b < 4; ++b) {
        edges.push_back((uint64_t{std::min(t[a], t[b])} << 32) | std::max(t[a], t[b]));
      }
    }
  }
  std::sort(edges.begin(), edges.end());
  uint64_t most = 0;
  int64_t most_count = 0;
  for (size_t i = 0; i < edges.size();) {
    size_t j = i;
    while (j < edges.size() && edges[j] == edges[i]) ++j;
    if (static_cast<int64_t>(j - i) > most_count) {
      most_count = static_cast<int64_t>(j - i);
      most = edges[i];
    }
    i = j;
  }
  return absl::InvalidArgumentError(absl::StrCat(
      "mesh is too crowded to check in bounded time: more than ", max_pairs, " pairs of a ", pair,
      " (at most ", kMaxCrowdedPairsPerItem, " per item are expected); the most crowded edge, (",
      most >> 32, ", ", most & 0xffffffffu, "), is shared by ", most_count,
      " tets (a mesh of a volume has tens): split or remesh the slivers around it"));
}

}  // namespace tetrefine
