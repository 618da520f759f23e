#include "core/alternative_tilings.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <set>
#include <string>
#include <vector>

#include "core/mesh.h"
#include "core/quality.h"
#include "core/tet_topology.h"
#include "core/tiling_check.h"
#include "core/vec3_ops.h"

namespace tetrefine {
namespace {

using Triangle = std::array<int, 3>;
using LocalTet = std::array<int, 4>;

// A tet with no symmetry and no special angle: every orientation and containment test on its
// corners and midpoints is decided by a wide margin, and holds for every other tet.
constexpr std::array<Vec3, 4> kReference = {
    {{0.1, 0.05, 0.02}, {1.03, 0.11, 0.07}, {0.37, 0.91, 0.13}, {0.29, 0.33, 0.87}}};

Triangle SortedFace(const LocalTet& t, int without) {
  Triangle f{};
  int k = 0;
  for (int j = 0; j < 4; ++j) {
    if (j != without) f[k++] = t[j];
  }
  std::sort(f.begin(), f.end());
  return f;
}

// Advancing-front enumeration of the tilings of a polyhedron whose boundary triangles are given
// with the side the inside lies on. A tet is added on the first open face (in sorted order) with
// an apex on its inner side; its other faces close open faces or open new ones. A tet may
// contain no other point, not even on its boundary (the children must meet face to face).
class TilingSearch {
 public:
  TilingSearch(const std::array<Vec3, kNumLocalPoints>& points, std::vector<int> vertices,
               double volume6)
      : points_(points), vertices_(std::move(vertices)), volume6_(volume6) {}

  // side: +1 when the inside is where SignedVolume6(f[0], f[1], f[2], x) > 0.
  void Open(const Triangle& f, int side) { open_[f] = side; }

  std::vector<std::vector<LocalTet>> Run() {
    Step();
    return found_;
  }

 private:
  double Volume6(const Triangle& f, int apex) const {
    return SignedVolume6(points_[f[0]], points_[f[1]], points_[f[2]], points_[apex]);
  }

  bool ContainsAnotherPoint(const LocalTet& t) const {
    const auto& p = points_;
    const double d = SignedVolume6(p[t[0]], p[t[1]], p[t[2]], p[t[3]]);
    for (int v : vertices_) {
      if (v == t[0] || v == t[1] || v == t[2] || v == t[3]) continue;
      const double l0 = SignedVolume6(p[v], p[t[1]], p[t[2]], p[t[3]]) / d;
      const double l1 = SignedVolume6(p[t[0]], p[v], p[t[2]], p[t[3]]) / d;
      const double l2 = SignedVolume6(p[t[0]], p[t[1]], p[v], p[t[3]]) / d;
      const double l3 = SignedVolume6(p[t[0]], p[t[1]], p[t[2]], p[v]) / d;
      constexpr double kOn = -1e-9;  // on a face or an edge counts as inside
      if (l0 > kOn && l1 > kOn && l2 > kOn && l3 > kOn) return true;
    }
    return false;
  }

  void Step() {
    if (found_.size() > 16) return;  // far more than any key has: a bug, reported by the caller
    if (open_.empty()) {
      if (std::abs(volume_ - volume6_) <= 1e-9 * volume6_) found_.push_back(tets_);
      return;
    }
    const auto [face, side] = *open_.begin();
    for (int apex : vertices_) {
      if (apex == face[0] || apex == face[1] || apex == face[2]) continue;
      const double v = Volume6(face, apex) * side;
      if (v <= 1e-12 * volume6_ || volume_ + v > volume6_ * (1 + 1e-9)) continue;
      const LocalTet t = {face[0], face[1], face[2], apex};
      if (ContainsAnotherPoint(t)) continue;
      std::vector<std::pair<Triangle, int>> closed_now, opened_now;
      bool fits = true;
      for (int k = 0; k < 4 && fits; ++k) {
        const Triangle f = SortedFace(t, k);
        // The side of f this tet lies on.
        const int tet_side = Volume6(f, t[k]) > 0 ? 1 : -1;
        const auto it = open_.find(f);
        if (it != open_.end()) {
          fits = it->second == tet_side;
          if (!fits) break;
          closed_now.push_back(*it);
          open_.erase(it);
          closed_.insert(f);
        } else if (closed_.count(f) != 0) {
          fits = false;
        } else {
          open_[f] = -tet_side;
          opened_now.push_back({f, -tet_side});
        }
      }
      if (fits) {
        tets_.push_back(t);
        volume_ += v;
        Step();
        volume_ -= v;
        tets_.pop_back();
      }
      for (const auto& [f, s] : opened_now) open_.erase(f);
      for (const auto& [f, s] : closed_now) {
        open_[f] = s;
        closed_.erase(f);
      }
    }
  }

  const std::array<Vec3, kNumLocalPoints>& points_;
  const std::vector<int> vertices_;
  const double volume6_;
  std::map<Triangle, int> open_;
  std::set<Triangle> closed_;
  std::vector<LocalTet> tets_;
  double volume_ = 0.0;
  std::vector<std::vector<LocalTet>> found_;
};

std::vector<LocalTet> SortedTets(std::vector<LocalTet> tets) {
  for (auto& t : tets) std::sort(t.begin(), t.end());
  std::sort(tets.begin(), tets.end());
  return tets;
}

[[noreturn]] void Die(uint32_t key, const std::string& what) {
  std::fprintf(stderr, "tetrefine: alternative tilings of key %u: %s\n", key, what.c_str());
  std::abort();
}

AlternativeTilings FindAlternatives(uint32_t key, const SubdivisionEntry& entry) {
  AlternativeTilings out;
  if (!entry.valid || entry.steiner || entry.configuration == Configuration::k0) return out;
  const auto points = LocalPoints(kReference, entry);
  const double volume6 = SignedVolume6(kReference[0], kReference[1], kReference[2], kReference[3]);
  std::vector<LocalTet> primary;
  std::map<Triangle, std::pair<int, int>> faces;  // face -> (uses, opposite point)
  for (int i = 0; i < entry.tet_count; ++i) {
    const LocalTet t = {entry.tets[i][0], entry.tets[i][1], entry.tets[i][2], entry.tets[i][3]};
    primary.push_back(t);
    for (int k = 0; k < 4; ++k) {
      auto& use = faces[SortedFace(t, k)];
      ++use.first;
      use.second = t[k];
    }
  }
  std::vector<int> vertices = {0, 1, 2, 3};
  for (int e = 0; e < 6; ++e) {
    if ((key & EdgeBit(e)) != 0) vertices.push_back(4 + e);
  }
  TilingSearch search(points, vertices, volume6);
  std::vector<Triangle> boundary;
  for (const auto& [f, use] : faces) {
    if (use.first != 1) continue;
    boundary.push_back(f);
    search.Open(f, SignedVolume6(points[f[0]], points[f[1]], points[f[2]], points[use.second]) > 0
                       ? 1
                       : -1);
  }
  const std::vector<LocalTet> primary_sorted = SortedTets(primary);
  bool primary_found = false;
  for (std::vector<LocalTet> tiling : search.Run()) {
    if (SortedTets(tiling) == primary_sorted) {
      primary_found = true;
      continue;
    }
    for (auto& t : tiling) {
      if (SignedVolume6(points[t[0]], points[t[1]], points[t[2]], points[t[3]]) < 0) {
        std::swap(t[2], t[3]);
      }
    }
    std::string why;
    if (!IsTiling(tiling, boundary, points, &why)) Die(key, "a tiling found is not one: " + why);
    if (out.count == kMaxAlternativeTilings) Die(key, "more tilings than kMaxAlternativeTilings");
    SubdivisionEntry& alt = out.entries[out.count++];
    alt.valid = true;
    alt.configuration = entry.configuration;
    alt.tet_count = static_cast<uint8_t>(tiling.size());
    for (size_t i = 0; i < tiling.size(); ++i) {
      for (int k = 0; k < 4; ++k) alt.tets[i][k] = static_cast<uint8_t>(tiling[i][k]);
    }
  }
  // The search must see the table's own tiling: if it does not, it misses tilings.
  if (!primary_found) Die(key, "the search does not find the table's tiling");
  return out;
}

std::array<AlternativeTilings, kNumSubdivisionKeys> BuildAlternativeTilingTable() {
  std::array<AlternativeTilings, kNumSubdivisionKeys> table{};
  const auto& entries = SubdivisionTable();
  for (uint32_t key = 0; key < kNumSubdivisionKeys; ++key) {
    table[key] = FindAlternatives(key, entries[key]);
  }
  return table;
}

// A child's corner points in lexicographic order: its quality and its place in the tie-break
// then depend on its points only, not on the order the parent's vertices came in.
std::array<Vec3, 4> SortedChild(const std::array<Vec3, kNumLocalPoints>& local,
                                const std::array<uint8_t, 4>& child) {
  std::array<Vec3, 4> c = {local[child[0]], local[child[1]], local[child[2]], local[child[3]]};
  std::sort(c.begin(), c.end(), LexLess);
  return c;
}

// The parts of each child one BestTiling call has measured, by its set of local points. The
// tilings of a key share children (configuration 6's four corner tets, the face-side tets of 4b
// and 5), and a shared child has the same sorted points, so the same parts: each is measured
// once. A child's points are put in lexicographic order through the ranks of the tet's local
// points, sorted once per call: sorting each child's four points (std::sort through LexLess) was
// most of BestTiling's time (2026-11-25, interleaved, random tets of the 75 keys with other
// tilings: 1.12-1.54 us per call before, 0.62-0.91 us with this class; the same answers).
class ChildParts {
 public:
  explicit ChildParts(const std::array<Vec3, kNumLocalPoints>& local) : local_(local) {
    static_assert(kNumLocalPoints <= 32);
    for (int i = 0; i < kNumLocalPoints; ++i) by_rank_[i] = static_cast<uint8_t>(i);
    // Insertion sort of 11 indices; equal points (none in a valid tet) would be equal in any
    // order.
    for (int i = 1; i < kNumLocalPoints; ++i) {
      const uint8_t v = by_rank_[i];
      int j = i;
      for (; j > 0 && LexLess(local[v], local[by_rank_[j - 1]]); --j) by_rank_[j] = by_rank_[j - 1];
      by_rank_[j] = v;
    }
    for (int r = 0; r < kNumLocalPoints; ++r) rank_[by_rank_[r]] = static_cast<uint8_t>(r);
  }

  const MeanRatioParts& Of(const std::array<uint8_t, 4>& child) {
    const uint32_t set = (1u << rank_[child[0]]) | (1u << rank_[child[1]]) |
                         (1u << rank_[child[2]]) | (1u << rank_[child[3]]);
    for (int i = 0; i < count_; ++i) {
      if (set_[i] == set) return parts_[i];
    }
    // The set's ranks in increasing order are the child's points in lexicographic order.
    std::array<const Vec3*, 4> sorted;
    uint32_t rest = set;
    for (const Vec3*& point : sorted) {
      point = &local_[by_rank_[std::countr_zero(rest)]];
      rest &= rest - 1;
    }
    set_[count_] = set;
    parts_[count_] = MeanRatioPartsOf(*sorted[0], *sorted[1], *sorted[2], *sorted[3]);
    return parts_[count_++];
  }

 private:
  static constexpr int kMaxChildren =
      (kMaxAlternativeTilings + 1) *
      static_cast<int>(std::tuple_size_v<decltype(SubdivisionEntry::tets)>);
  const std::array<Vec3, kNumLocalPoints>& local_;
  std::array<uint8_t, kNumLocalPoints> by_rank_;  // local point of each rank
  std::array<uint8_t, kNumLocalPoints> rank_;     // rank of each local point
  int count_ = 0;
  std::array<uint32_t, kMaxChildren> set_;
  std::array<MeanRatioParts, kMaxChildren> parts_;
};

double WorstOf(const SubdivisionEntry& entry, ChildParts& measured) {
  std::array<MeanRatioParts, std::tuple_size_v<decltype(entry.tets)>> parts;
  for (int i = 0; i < entry.tet_count; ++i) parts[i] = measured.Of(entry.tets[i]);
  return std::min(1.0, MinMeanRatio(parts.data(), entry.tet_count));
}

bool PointsLess(const std::array<Vec3, 4>& a, const std::array<Vec3, 4>& b) {
  return std::lexicographical_compare(a.begin(), a.end(), b.begin(), b.end(), LexLess);
}

// The tiling's children, each as its sorted points, sorted: a key that depends on geometry only.
std::vector<std::array<Vec3, 4>> GeometricKey(const SubdivisionEntry& entry,
                                              const std::array<Vec3, kNumLocalPoints>& local) {
  std::vector<std::array<Vec3, 4>> children;
  for (int i = 0; i < entry.tet_count; ++i) children.push_back(SortedChild(local, entry.tets[i]));
  std::sort(children.begin(), children.end(), PointsLess);
  return children;
}

}  // namespace

const std::array<AlternativeTilings, kNumSubdivisionKeys>& AlternativeTilingTable() {
  static const auto* table =
      new std::array<AlternativeTilings, kNumSubdivisionKeys>(BuildAlternativeTilingTable());
  return *table;
}

const SubdivisionEntry& TilingEntry(uint32_t tiling_key) {
  const uint32_t key = tiling_key & (kNumSubdivisionKeys - 1);
  const uint32_t which = tiling_key >> kTilingShift;
  if (which == 0) return SubdivisionTable()[key];
  return AlternativeTilingTable()[key].entries[which - 1];
}

TilingChoice ChooseTiling(uint32_t key, const std::array<Vec3, 4>& corners) {
  const AlternativeTilings& alternatives = AlternativeTilingTable()[key];
  const SubdivisionEntry& table_entry = SubdivisionTable()[key];
  const auto local = LocalPoints(corners, table_entry);
  int best = 0;
  const SubdivisionEntry* best_entry = &table_entry;
  ChildParts measured(local);
  double best_quality = WorstOf(table_entry, measured);
  for (int i = 1; i <= alternatives.count; ++i) {
    const SubdivisionEntry& entry = alternatives.entries[i - 1];
    const double q = WorstOf(entry, measured);
    bool better = q > best_quality;
    if (q == best_quality) {
      if (entry.tet_count != best_entry->tet_count) {
        better = entry.tet_count < best_entry->tet_count;
      } else if (best != 0) {
        const auto a = GeometricKey(entry, local), b = GeometricKey(*best_entry, local);
        better = std::lexicographical_compare(a.begin(), a.end(), b.begin(), b.end(), PointsLess);
      }
    }
    if (better) {
      best = i;
      best_entry = &entry;
      best_quality = q;
    }
  }
  return {key | (static_cast<uint32_t>(best) << kTilingShift), best_quality};
}

uint32_t BestTiling(uint32_t key, const std::array<Vec3, 4>& corners) {
  // A key without other tilings needs no measuring.
  if (AlternativeTilingTable()[key].count == 0) return key;
  return ChooseTiling(key, corners).tiling;
}

}  // namespace tetrefine
