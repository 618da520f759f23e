#include "core/edge_marking.h"

#include <algorithm>
#include <atomic>
#include <bit>
#include <cmath>
#include <vector>

#include "core/alternative_tilings.h"
#include "core/lattice_kernel.h"
#include "core/parallel.h"
#include "core/quality.h"
#include "core/segment_error.h"
#include "core/subdivision_table.h"
#include "core/tet_topology.h"
#include "core/vec3_ops.h"

namespace tetrefine::refine_internal {
namespace {

// Marks edge e split. Many tets may mark the same edge at once; they all write 1.
void MarkSplit(FillLater<uint8_t>& split, uint32_t e) {
  std::atomic_ref<uint8_t>(split[e]).store(1, std::memory_order_relaxed);
}

// The marks a pass over the tets decided, per block, applied after the pass: every tet reads
// the marks as they were before it (so the result does not depend on the order tets are
// visited in) without a copy of the whole mark array per pass. Copying the marks and comparing
// the copies cost a fresh E-byte array, and two E-byte scans, per closure round and guard pass:
// T1 brain `--block 4` mesh at eps 0.05, one thread, its last three iterations took 0.49-0.54,
// 0.35-0.39 and 0.33-0.37 s with pending marks against 0.55-0.58, 0.37-0.45 and 0.39-0.50 s
// with copies (2026-11-24, interleaved, identical output).
class PendingMarks {
 public:
  explicit PendingMarks(int64_t num_tets) : blocks_(static_cast<size_t>(BlockCount(num_tets))) {}
  // Called by block b's pass only.
  void Add(int64_t b, uint32_t e) { blocks_[b].push_back(e); }
  // Sets the pending marks; returns how many edges were not split before (each counted once),
  // and appends those edges to `fresh` when it is not null.
  int64_t Apply(FillLater<uint8_t>& split, std::vector<uint32_t>* fresh) {
    int64_t added = 0;
    for (const std::vector<uint32_t>& block : blocks_) {
      for (uint32_t e : block) {
        if (split[e] != 0) continue;
        ++added;
        split[e] = 1;
        if (fresh != nullptr) fresh->push_back(e);
      }
    }
    return added;
  }

 private:
  std::vector<std::vector<uint32_t>> blocks_;
};

// Calls body(block, t) for every tet of the pass: all tets, or the listed ones.
template <typename Body>
void ForEachVisitedTet(int64_t num_tets, const std::vector<uint32_t>* visit, Body body,
                       CancelFlag& cancel) {
  const int64_t n = visit == nullptr ? num_tets : static_cast<int64_t>(visit->size());
  ForEachBlock(n, [&](int64_t b, int64_t begin, int64_t end) {
    if (cancel.Check()) return;
    for (int64_t i = begin; i < end; ++i) body(b, visit == nullptr ? i : (*visit)[i]);
  });
}

int64_t PassSize(int64_t num_tets, const std::vector<uint32_t>* visit) {
  return visit == nullptr ? num_tets : static_cast<int64_t>(visit->size());
}

// The local edges of each face (kTetFaces order), and the same as EdgeBit masks.
constexpr std::array<std::array<int, 3>, 4> kFaceEdges = [] {
  std::array<std::array<int, 3>, 4> edges{};
  for (int f = 0; f < 4; ++f) {
    const auto& c = kTetFaces[f];
    edges[f] = {EdgeIndex(c[0], c[1]), EdgeIndex(c[0], c[2]), EdgeIndex(c[1], c[2])};
  }
  return edges;
}();
constexpr std::array<uint32_t, 4> kFaceEdgeBits = [] {
  std::array<uint32_t, 4> bits{};
  for (int f = 0; f < 4; ++f) {
    for (int e : kFaceEdges[f]) bits[f] |= EdgeBit(e);
  }
  return bits;
}();

// The order of a tet's six edges by length, equal lengths broken by geometry: the edge whose
// lexicographically smaller endpoint, then larger endpoint, is smaller counts as longer. Every
// tet sharing an edge (or a face) orders it the same way, so shards agree.
class EdgeOrder {
 public:
  explicit EdgeOrder(const std::array<Vec3, 4>& p) : p_(p) {
    for (int k = 0; k < 6; ++k) {
      length_[k] = SquaredDistance(p[kTetEdges[k][0]], p[kTetEdges[k][1]]);
    }
  }
  // Whether local edge a is longer than local edge b != a.
  bool Longer(int a, int b) const {
    if (length_[a] != length_[b]) return length_[a] > length_[b];
    const Vec3& a0 = p_[kTetEdges[a][0]];
    const Vec3& a1 = p_[kTetEdges[a][1]];
    const Vec3& b0 = p_[kTetEdges[b][0]];
    const Vec3& b1 = p_[kTetEdges[b][1]];
    const Vec3& a_lo = LexLess(a1, a0) ? a1 : a0;
    const Vec3& a_hi = LexLess(a1, a0) ? a0 : a1;
    const Vec3& b_lo = LexLess(b1, b0) ? b1 : b0;
    const Vec3& b_hi = LexLess(b1, b0) ? b0 : b1;
    return LexLess(a_lo, b_lo) || (a_lo == b_lo && LexLess(a_hi, b_hi));
  }
  // The longest of the six.
  int Longest() const {
    int best = 0;
    for (int k = 1; k < 6; ++k) {
      if (Longer(k, best)) best = k;
    }
    return best;
  }

 private:
  const std::array<Vec3, 4>& p_;
  std::array<double, 6> length_;
};

// Whether split pattern q holds the tet's longest edge (as longest-edge bisection cuts a tet)
// and, so that the closure adds nothing to it from this tet, the longest edge of every face with
// a split edge (targets: ClosureTargets).
bool ClosedWithinTet(uint32_t q, uint32_t targets) {
  if ((q & EdgeBit(static_cast<int>(targets & 7u))) == 0) return false;
  for (int f = 0; f < 4; ++f) {
    if ((q & kFaceEdgeBits[f]) == 0) continue;
    if ((q & EdgeBit(static_cast<int>((targets >> (3 + 3 * f)) & 7u))) == 0) return false;
  }
  return true;
}

// Whether the edges of `a` (a set of local edges) are longer than those of `b`, a set of as
// many: both sorted longest first, the first place they differ decides.
bool LongerEdges(uint32_t a, uint32_t b, const EdgeOrder& order) {
  std::array<int, 6> ea{}, eb{};
  int na = 0, nb = 0;
  for (int k = 0; k < 6; ++k) {
    if ((a & EdgeBit(k)) != 0) ea[na++] = k;
    if ((b & EdgeBit(k)) != 0) eb[nb++] = k;
  }
  // Insertion sorts: at most six entries (std::sort inlined here tripped GCC 12's
  // -Warray-bounds on its 16-entry insertion threshold).
  const auto sort_longest_first = [&](std::array<int, 6>& e, int n) {
    for (int i = 1; i < n; ++i) {
      for (int j = i; j > 0 && order.Longer(e[j], e[j - 1]); --j) std::swap(e[j], e[j - 1]);
    }
  };
  sort_longest_first(ea, na);
  sort_longest_first(eb, nb);
  for (int i = 0; i < na && i < nb; ++i) {
    if (ea[i] != eb[i]) return order.Longer(ea[i], eb[i]);
  }
  return false;
}

// The ten points SubdivisionKey reads: the corners, then the midpoints of the six edges in
// kTetEdges order.
std::array<Vec3, 10> CornersAndMidpoints(const std::array<Vec3, 4>& corners) {
  std::array<Vec3, 10> p;
  for (int c = 0; c < 4; ++c) p[c] = corners[c];
  for (int k = 0; k < 6; ++k) p[4 + k] = Midpoint(p[kTetEdges[k][0]], p[kTetEdges[k][1]]);
  return p;
}

}  // namespace

GuardRemedy FewestGuardEdges(uint32_t pattern, const std::array<Vec3, 4>& corners,
                             double threshold) {
  const EdgeOrder order(corners);
  const uint32_t targets = ClosureTargets(corners);
  const std::array<Vec3, 10> p = CornersAndMidpoints(corners);
  const uint32_t unsplit = 63u & ~pattern;
  GuardRemedy best;
  double best_worst = -1.0;
  // By the number of added edges: the first size that has a remedy gives the answer. All six
  // (regular 1:8 refinement) is the fallback, taken without a look, as the guard always took it.
  for (int size = 1; size < std::popcount(unsplit); ++size) {
    for (uint32_t add = unsplit; add != 0; add = (add - 1) & unsplit) {
      if (std::popcount(add) != size) continue;
      const uint32_t q = pattern | add;
      if (!ClosedWithinTet(q, targets)) continue;
      const TilingChoice choice = ChooseTiling(SubdivisionKey(q, p), corners);
      if (choice.worst < threshold) continue;
      const bool better =
          choice.worst > best_worst ||
          (choice.worst == best_worst && LongerEdges(add, best.pattern & ~pattern, order));
      if (!better) continue;
      best.pattern = q;
      best.tiling = choice.tiling;
      best_worst = choice.worst;
    }
    if (best.pattern != 63) break;
  }
  return best;
}

EdgeErrors EvaluateEdges(const Volume& volume, const State& m, const EdgeTable& edges,
                         const EdgeTestParams& params, const KnownEdges* known,
                         CancelFlag& cancel) {
  const double min_length2 = params.min_edge_length * params.min_edge_length;
  const bool segment = params.test == EdgeTest::kSegment;
  EdgeErrors out;
  const std::vector<Vec3>& points = *m.points;
  const std::vector<double>& values = m.mesh.values;
  const int64_t nv = static_cast<int64_t>(points.size());
  out.mid_value.resize(edges.size());
  out.split.resize(edges.size());
  if (segment) out.segment_error.resize(edges.size());
  const bool known_segment = known != nullptr && !known->segment_error.empty();
  const int64_t blocks = BlockCount(nv);
  std::vector<double> sums(blocks, 0.0), maxs(blocks, 0.0), seg_maxs(blocks, 0.0);
  std::vector<int64_t> failing(blocks, 0), kept(blocks, 0);
  // Calls visit(e, w, known_index) for vertex v's edges e = (v, w) in order; known_index is the
  // edge's index in `known`, or -1. v's known edges are walked forward alongside its sorted new
  // ones.
  const auto for_each_edge = [&](int64_t v, auto visit) {
    const uint32_t* kp = nullptr;
    const uint32_t* ke = nullptr;
    if (known != nullptr && v + 1 < static_cast<int64_t>(known->edges.first.size())) {
      kp = known->edges.second.data() + known->edges.first[v];
      ke = known->edges.second.data() + known->edges.first[v + 1];
    }
    for (uint32_t e = edges.first[v]; e < edges.first[v + 1]; ++e) {
      const uint32_t w = edges.second[e];
      while (kp < ke && *kp < w) ++kp;
      visit(e, w, kp < ke && *kp == w ? kp - known->edges.second.data() : int64_t{-1});
    }
  };
  ForEachBlock(nv, [&](int64_t b, int64_t begin, int64_t end) {
    if (cancel.Check()) return;
    // First the midpoint values of the block's edges: known ones copied, new ones sampled a batch
    // at a time (SampleIndices, four at a time with AVX2; the same bits as SampleInside, whose
    // clamp to the grid SampleIndex applies anyway). Then the tests, in edge order, so that the
    // sums keep their order. Midpoint sampling was a tenth of a one-thread file-to-file run.
    {
      constexpr int kBatch = 64;
      double ux[kBatch], uy[kBatch], uz[kBatch], sampled[kBatch];
      uint32_t batch_edge[kBatch];
      int n = 0;
      const auto flush = [&] {
        lattice_internal::SampleIndices(volume, ux, uy, uz, n, sampled);
        for (int i = 0; i < n; ++i) out.mid_value[batch_edge[i]] = sampled[i];
        n = 0;
      };
      for (int64_t v = begin; v < end; ++v) {
        for_each_edge(v, [&](uint32_t e, uint32_t w, int64_t known_index) {
          if (known_index >= 0) {
            out.mid_value[e] = known->mid_value[known_index];
            return;
          }
          const Vec3 u = volume.ContinuousIndex(Midpoint(points[v], points[w]));
          ux[n] = u[0];
          uy[n] = u[1];
          uz[n] = u[2];
          batch_edge[n] = e;
          if (++n == kBatch) flush();
        });
      }
      if (n > 0) flush();
    }
    double s = 0.0, mx = 0.0, seg_mx = 0.0;
    int64_t n_failing = 0, n_kept = 0;
    for (int64_t v = begin; v < end; ++v) {
      for_each_edge(v, [&](uint32_t e, uint32_t w, int64_t known_index) {
        const bool is_known = known_index >= 0;
        const double real = out.mid_value[e];
        const double error = std::abs(real - 0.5 * (values[v] + values[w])) / params.norm;
        double test_error = error;
        if (segment) {
          test_error = is_known && known_segment
                           ? known->segment_error[known_index]
                           : MaxSegmentDiscrepancy(volume, points[v], points[w], values[v],
                                                   values[w], params.clamp) /
                                 params.norm;
          // The midpoint is a point of the segment: the two agree up to rounding, and the
          // statistic must never say the midpoint is worse than the whole edge.
          test_error = std::max(test_error, error);
          out.segment_error[e] = test_error;
          seg_mx = std::max(seg_mx, test_error);
        }
        bool split = test_error > params.epsilon;
        if (split && min_length2 > 0.0 && SquaredDistance(points[v], points[w]) < min_length2) {
          split = false;
          ++n_kept;
        }
        out.split[e] = split;
        n_failing += split;
        s += error;
        mx = std::max(mx, error);
      });
    }
    sums[b] = s;
    maxs[b] = mx;
    seg_maxs[b] = seg_mx;
    failing[b] = n_failing;
    kept[b] = n_kept;
  });
  double sum = 0.0;
  for (int64_t b = 0; b < blocks; ++b) {
    sum += sums[b];
    out.max_error = std::max(out.max_error, maxs[b]);
    out.max_segment_error = std::max(out.max_segment_error, seg_maxs[b]);
    out.failing += failing[b];
    out.short_kept += kept[b];
  }
  out.mean_error = edges.size() > 0 ? sum / static_cast<double>(edges.size()) : 0.0;
  return out;
}

int LongestEdge(const std::array<Vec3, 4>& p) { return EdgeOrder(p).Longest(); }

uint32_t ClosureTargets(const std::array<Vec3, 4>& p) {
  const EdgeOrder order(p);
  uint32_t targets = static_cast<uint32_t>(order.Longest());
  for (int f = 0; f < 4; ++f) {
    const std::array<int, 3>& e = kFaceEdges[f];
    int face_longest = e[0];
    if (order.Longer(e[1], face_longest)) face_longest = e[1];
    if (order.Longer(e[2], face_longest)) face_longest = e[2];
    targets |= static_cast<uint32_t>(face_longest) << (3 + 3 * f);
  }
  return targets;
}

int64_t ClosureRound(const std::vector<Vec3>& points, const std::vector<Tet>& tets,
                     const EdgeTable& edges, FillLater<uint8_t>& split, CancelFlag& cancel,
                     FillLater<uint16_t>& cache, const std::vector<uint32_t>* visit,
                     std::vector<uint32_t>* fresh) {
  PendingMarks next(PassSize(static_cast<int64_t>(tets.size()), visit));
  const auto rule = [&](int64_t b, int64_t t) {
    const auto& te = edges.tet_edges[t];
    uint32_t pattern = 0;
    for (int k = 0; k < 6; ++k) pattern |= split[te[k]] != 0 ? EdgeBit(k) : 0u;
    if (pattern == 0) return;
    // Only this block reads or writes cache[t]: no two threads share an entry (a visit list
    // names a tet once).
    if (cache[t] == kTargetsUnknown) {
      const Tet& tet = tets[t];
      cache[t] = static_cast<uint16_t>(
          ClosureTargets({points[tet[0]], points[tet[1]], points[tet[2]], points[tet[3]]}));
    }
    const uint32_t r = cache[t];
    const auto add = [&](uint32_t k) {
      if ((pattern & EdgeBit(static_cast<int>(k))) == 0) next.Add(b, te[k]);
    };
    // Faces only, as Plaza's rule: the tet's own longest edge (r & 7) is not added. Measured
    // 2026-11-28 (docs/schemes.md "The closure without the tet rule"): 3.1% fewer tets on the 20
    // reproduction runs and 3.1% on the 22 unseen ones, runs above Plaza's tets 14 -> 12 and
    // 18 -> 5 (of the runs both converge on); the worst tet the same or better in the unseen runs
    // but lower in three structured reproduction runs (Marschner-Lobb blocks, heart2).
    for (int f = 0; f < 4; ++f) {
      if ((pattern & kFaceEdgeBits[f]) != 0) add((r >> (3 + 3 * f)) & 7u);
    }
  };
  ForEachVisitedTet(static_cast<int64_t>(tets.size()), visit, rule, cancel);
  if (cancel.IsSet()) return 0;
  return next.Apply(split, fresh);
}

int64_t CloseToLongestEdges(const std::vector<Vec3>& points, const std::vector<Tet>& tets,
                            const EdgeTable& edges, int rounds, FillLater<uint8_t>& split,
                            CancelFlag& cancel, FillLater<uint16_t>* targets) {
  FillLater<uint16_t> own;
  if (targets == nullptr) {
    own.assign(tets.size(), kTargetsUnknown);
    targets = &own;
  }
  // Every round visits every tet. Tried 2026-11-24: from the second round on, visiting only the
  // tets with two vertices at the ends of an edge the round before added (a byte per vertex,
  // found in a pass over the edge table) - the same marks (tests/core/edge_marking_test.cc
  // checks the rounds against that rule), but no faster: the T1 brain `--block 4` mesh at eps
  // 0.05, one thread, late iterations 0.76-1.41 s against 0.69-1.32 s, interleaved. The extra
  // pass over the edges and the tets' vertex reads cost what the skipped edge reads saved.
  // Refine visits fewer tets another way: core/marking_sequence.h.
  int64_t added = 0;
  for (int round = 0; round < rounds; ++round) {
    const int64_t round_added =
        ClosureRound(points, tets, edges, split, cancel, *targets, nullptr, nullptr);
    if (cancel.IsSet()) return added;
    added += round_added;
    if (round_added == 0) break;
  }
  return added;
}

int64_t GuardPass(const std::vector<Vec3>& points, const std::vector<Tet>& tets,
                  const EdgeTable& edges, double ratio, double floor, bool best_tiling,
                  FillLater<uint8_t>& split, CancelFlag& cancel, const std::vector<uint32_t>* visit,
                  std::vector<uint32_t>* fresh, FillLater<uint16_t>* tilings) {
  const auto& table = SubdivisionTable();
  PendingMarks next(PassSize(static_cast<int64_t>(tets.size()), visit));
  const auto rule = [&](int64_t b, int64_t t) {
    const auto& te = edges.tet_edges[t];
    uint32_t pattern = 0;
    for (int k = 0; k < 6; ++k) pattern |= split[te[k]] ? EdgeBit(k) : 0u;
    if (pattern == 0 || pattern == 63) return;
    const Tet& tet = tets[t];
    const std::array<Vec3, 4> corners = {points[tet[0]], points[tet[1]], points[tet[2]],
                                         points[tet[3]]};
    const std::array<Vec3, 10> p = CornersAndMidpoints(corners);
    const uint32_t key = SubdivisionKey(pattern, p);
    // The tiling Subdivide will cut the tet by.
    const uint32_t tiling = best_tiling ? BestTiling(key, corners) : key;
    // Only this block writes tilings[t]: a visit list names a tet once.
    if (best_tiling && tilings != nullptr) (*tilings)[t] = static_cast<uint16_t>(tiling);
    const SubdivisionEntry& entry = best_tiling ? TilingEntry(tiling) : table[key];
    const auto local = LocalPoints(corners, entry);
    const double threshold =
        std::max(ratio * MeanRatio(corners[0], corners[1], corners[2], corners[3]), floor);
    bool bad = false;
    for (int i = 0; i < entry.tet_count && !bad; ++i) {
      const auto& c = entry.tets[i];
      bad = MeanRatioBelow(MeanRatioPartsOf(local[c[0]], local[c[1]], local[c[2]], local[c[3]]),
                           threshold);
    }
    if (!bad) return;
    uint32_t remedy = 63;
    if (best_tiling) {
      const GuardRemedy r = FewestGuardEdges(pattern, corners, threshold);
      remedy = r.pattern;
      // The key the tet will most likely be cut by; Subdivide checks that it is still its key.
      if (tilings != nullptr && r.tiling != kUnknownTiling) {
        (*tilings)[t] = static_cast<uint16_t>(r.tiling);
      }
    }
    for (int k = 0; k < 6; ++k) {
      if ((remedy & EdgeBit(k)) != 0 && !split[te[k]]) next.Add(b, te[k]);
    }
  };
  ForEachVisitedTet(static_cast<int64_t>(tets.size()), visit, rule, cancel);
  if (cancel.IsSet()) return 0;
  return next.Apply(split, fresh);
}

int64_t PromoteBadSplits(const std::vector<Vec3>& points, const std::vector<Tet>& tets,
                         const EdgeTable& edges, double ratio, double floor, bool best_tiling,
                         FillLater<uint8_t>& split, CancelFlag& cancel) {
  return GuardPass(points, tets, edges, ratio, floor, best_tiling, split, cancel, nullptr, nullptr);
}

double WorstChildOf(uint32_t pattern, const std::array<Vec3, 4>& corners) {
  if (pattern == 0) return MeanRatio(corners[0], corners[1], corners[2], corners[3]);
  return ChooseTiling(SubdivisionKey(pattern, CornersAndMidpoints(corners)), corners).worst;
}

GuardRemedy SparingGuardEdges(uint32_t pattern, const std::array<Vec3, 4>& corners,
                              double threshold, absl::FunctionRef<bool(uint32_t add)> spares) {
  const EdgeOrder order(corners);
  const std::array<Vec3, 10> p = CornersAndMidpoints(corners);
  const uint32_t unsplit = 63u & ~pattern;
  GuardRemedy best{pattern, kUnknownTiling};
  double best_worst = -1.0;
  // By the number of added edges, all of them (regular 1:8 refinement) included: the first size
  // with a remedy gives the answer. The neighbours are asked last, for the candidates that would
  // win on their own merits.
  for (int size = 1; size <= std::popcount(unsplit); ++size) {
    for (uint32_t add = unsplit; add != 0; add = (add - 1) & unsplit) {
      if (std::popcount(add) != size) continue;
      const TilingChoice choice = ChooseTiling(SubdivisionKey(pattern | add, p), corners);
      if (choice.worst < threshold) continue;
      const bool better =
          choice.worst > best_worst ||
          (choice.worst == best_worst && LongerEdges(add, best.pattern & ~pattern, order));
      if (!better || !spares(add)) continue;
      best.pattern = pattern | add;
      best.tiling = choice.tiling;
      best_worst = choice.worst;
    }
    if (best.pattern != pattern) break;
  }
  return best;
}

int64_t FinalGuardPass(const std::vector<Vec3>& points, const std::vector<Tet>& tets,
                       const EdgeTable& edges, const TetsAround& around, double ratio, double floor,
                       FillLater<uint8_t>& split, CancelFlag& cancel,
                       const std::vector<uint32_t>* visit, std::vector<uint32_t>* fresh,
                       FillLater<uint16_t>* tilings) {
  const auto corners_of = [&](uint32_t t) {
    const Tet& tet = tets[t];
    return std::array<Vec3, 4>{points[tet[0]], points[tet[1]], points[tet[2]], points[tet[3]]};
  };
  const auto pattern_of = [&](uint32_t t) {
    const auto& te = edges.tet_edges[t];
    uint32_t pattern = 0;
    for (int k = 0; k < 6; ++k) pattern |= split[te[k]] ? EdgeBit(k) : 0u;
    return pattern;
  };
  const auto threshold_of = [&](const std::array<Vec3, 4>& c) {
    return std::max(ratio * MeanRatio(c[0], c[1], c[2], c[3]), floor);
  };
  PendingMarks next(PassSize(static_cast<int64_t>(tets.size()), visit));
  const auto rule = [&](int64_t b, int64_t t) {
    const uint32_t pattern = pattern_of(static_cast<uint32_t>(t));
    if (pattern == 0 || pattern == 63) return;
    const std::array<Vec3, 4> corners = corners_of(static_cast<uint32_t>(t));
    const std::array<Vec3, 10> p = CornersAndMidpoints(corners);
    const TilingChoice choice = ChooseTiling(SubdivisionKey(pattern, p), corners);
    // Only this block writes tilings[t]: a visit list names a tet once.
    if (tilings != nullptr) (*tilings)[t] = static_cast<uint16_t>(choice.tiling);
    const double threshold = threshold_of(corners);
    if (choice.worst >= threshold) return;
    const auto& te = edges.tet_edges[t];
    const Tet& tet = tets[t];
    std::vector<uint32_t> neighbours;
    const auto spares = [&](uint32_t add) {
      neighbours.clear();
      for (int k = 0; k < 6; ++k) {
        if ((add & EdgeBit(k)) == 0) continue;
        around.ForEachOnEdge(tet[kTetEdges[k][0]], tet[kTetEdges[k][1]], tets, [&](uint32_t s) {
          if (s != static_cast<uint32_t>(t)) neighbours.push_back(s);
        });
      }
      std::sort(neighbours.begin(), neighbours.end());
      neighbours.erase(std::unique(neighbours.begin(), neighbours.end()), neighbours.end());
      for (uint32_t s : neighbours) {
        const uint32_t before = pattern_of(s);
        uint32_t after = before;
        for (int j = 0; j < 6; ++j) {
          for (int k = 0; k < 6; ++k) {
            if ((add & EdgeBit(k)) != 0 && edges.tet_edges[s][j] == te[k]) after |= EdgeBit(j);
          }
        }
        if (after == before) continue;
        const std::array<Vec3, 4> c = corners_of(s);
        const double worst_after = WorstChildOf(after, c);
        if (worst_after < threshold_of(c) && worst_after < WorstChildOf(before, c)) return false;
      }
      return true;
    };
    const GuardRemedy remedy = SparingGuardEdges(pattern, corners, threshold, spares);
    if (remedy.pattern == pattern) return;
    if (tilings != nullptr) (*tilings)[t] = static_cast<uint16_t>(remedy.tiling);
    for (int k = 0; k < 6; ++k) {
      if ((remedy.pattern & ~pattern & EdgeBit(k)) != 0) next.Add(b, te[k]);
    }
  };
  ForEachVisitedTet(static_cast<int64_t>(tets.size()), visit, rule, cancel);
  if (cancel.IsSet()) return 0;
  return next.Apply(split, fresh);
}

int64_t MarkFailingTets(const Volume& volume, State& state, const EdgeTable& edges, int n,
                        const EdgeTestParams& params, FillLater<uint8_t>& split, CancelFlag& cancel,
                        int64_t* kept) {
  const std::vector<Vec3>& points = *state.points;
  const double min_length2 = params.min_edge_length * params.min_edge_length;
  std::vector<int64_t> short_kept(
      static_cast<size_t>(BlockCount(static_cast<int64_t>(state.tets->size()))), 0);
  const std::vector<Tet>& tets = *state.tets;
  const std::vector<double>& values = state.mesh.values;
  const int64_t nt = static_cast<int64_t>(tets.size());
  const int64_t blocks = BlockCount(nt);
  std::vector<int64_t> failing(blocks, 0);
  // With the corners (where the discrepancy is 0 by construction: 4 points of 165 for n = 8) so
  // that a passing tet's sum is the final verification's, which then reads it instead of sampling
  // the tet again (SampleLattice's `known`).
  const lattice_internal::LatticePoints lattice(n, /*with_corners=*/true);
  ForEachBlock(nt, [&](int64_t b, int64_t begin, int64_t end) {
    if (cancel.Check()) return;
    int64_t f = 0;
    for (int64_t t = begin; t < end; ++t) {
      if (state.tet_lattice_error[t] >= 0.0) continue;
      const Tet& tet = tets[t];
      const std::array<Vec3, 4> p = {points[tet[0]], points[tet[1]], points[tet[2]],
                                     points[tet[3]]};
      const lattice_internal::LatticeCheck check = lattice_internal::CheckLatticeUntil(
          volume, lattice, p, {values[tet[0]], values[tet[1]], values[tet[2]], values[tet[3]]},
          params.norm, params.epsilon);
      state.tet_lattice_error[t] = check.max_error;
      if (check.passed) {
        state.tet_lattice_sum[t] = check.sum_error;
        continue;
      }
      const int longest = LongestEdge(p);
      if (min_length2 > 0.0 &&
          SquaredDistance(p[kTetEdges[longest][0]], p[kTetEdges[longest][1]]) < min_length2) {
        ++short_kept[b];
        continue;
      }
      ++f;
      MarkSplit(split, edges.tet_edges[t][longest]);
    }
    failing[b] = f;
  });
  int64_t total = 0;
  for (int64_t f : failing) total += f;
  *kept = 0;
  for (int64_t k : short_kept) *kept += k;
  return total;
}

}  // namespace tetrefine::refine_internal
