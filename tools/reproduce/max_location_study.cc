#include "tools/reproduce/max_location_study.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <random>

#include "core/lattice.h"
#include "tbb/blocked_range.h"
#include "tbb/parallel_reduce.h"
#include "tools/reproduce/uniform_refine.h"

namespace tetrefine::reproduce {
namespace {

constexpr int kN = 8;

struct Argmax {
  double error = 0.0;
  std::array<int, 4> at{kN, 0, 0, 0};
};

// The same scan as core's SampleTetLattice (same order, same strict comparison), keeping the
// point.
Argmax ScanTet(const Volume& volume, const Mesh& mesh, int64_t t, double norm) {
  const Tet& tet = mesh.tets[t];
  Argmax best;
  bool first = true;
  for (int i = 0; i <= kN; ++i) {
    for (int j = 0; i + j <= kN; ++j) {
      for (int k = 0; i + j + k <= kN; ++k) {
        const int l = kN - i - j - k;
        const double b[4] = {static_cast<double>(i) / kN, static_cast<double>(j) / kN,
                             static_cast<double>(k) / kN, static_cast<double>(l) / kN};
        Vec3 x{0, 0, 0};
        double approx = 0.0;
        for (int c = 0; c < 4; ++c) {
          for (int a = 0; a < 3; ++a) x[a] += b[c] * mesh.points[tet[c]][a];
          approx += b[c] * mesh.values[tet[c]];
        }
        const double e = std::abs(volume.Sample(x) - approx) / norm;
        if (first || e > best.error) {
          best = {e, {i, j, k, l}};
          first = false;
        }
      }
    }
  }
  return best;
}

bool NearEdgeMidpoint(const std::array<int, 4>& b) {
  for (int u = 0; u < 4; ++u) {
    for (int v = u + 1; v < 4; ++v) {
      int distance = 0;
      for (int c = 0; c < 4; ++c) distance += std::abs(b[c] - ((c == u || c == v) ? kN / 2 : 0));
      if (distance <= 2) return true;
    }
  }
  return false;
}

struct Partial {
  std::vector<LocationCounts> counts;
  int64_t mismatches = 0;
};

}  // namespace

LocationStudy StudyMaxLocation(const Volume& volume, Mesh mesh, double norm_coeff,
                               const std::vector<double>& thresholds, int64_t max_tets,
                               uint64_t seed) {
  if (mesh.values.size() != mesh.points.size()) SampleValues(volume, mesh);
  LocationStudy study;
  study.tets = static_cast<int64_t>(mesh.tets.size());
  std::vector<int64_t> chosen;
  if (study.tets > max_tets) {
    // Without replacement, so no tet counts twice.
    std::vector<int64_t> all(study.tets);
    for (int64_t i = 0; i < study.tets; ++i) all[i] = i;
    std::mt19937_64 rng(seed);
    std::shuffle(all.begin(), all.end(), rng);
    chosen.assign(all.begin(), all.begin() + max_tets);
  }
  const int64_t n = chosen.empty() ? study.tets : max_tets;
  study.tets_sampled = n;
  Partial empty;
  for (double t : thresholds) empty.counts.push_back({.threshold = t});
  const Partial total = tbb::parallel_reduce(
      tbb::blocked_range<int64_t>(0, n, 1024), empty,
      [&](const tbb::blocked_range<int64_t>& r, Partial acc) {
        for (int64_t s = r.begin(); s < r.end(); ++s) {
          const int64_t t = chosen.empty() ? s : chosen[s];
          const TetLattice core =
              SampleTetLattice(volume, mesh, t, kN, norm_coeff, /*epsilon=*/1.0, /*clamp=*/true);
          const Argmax own = ScanTet(volume, mesh, t, norm_coeff);
          if (LatticeLocation(kN, own.at) != core.max_location) ++acc.mismatches;
          for (LocationCounts& c : acc.counts) {
            if (!(core.max_error > c.threshold)) continue;
            ++c.counted;
            ++c.by_location[static_cast<int>(core.max_location)];
            if (NearEdgeMidpoint(own.at)) ++c.near_midpoint;
          }
        }
        return acc;
      },
      [](Partial a, const Partial& b) {
        for (size_t i = 0; i < a.counts.size(); ++i) {
          a.counts[i].counted += b.counts[i].counted;
          a.counts[i].near_midpoint += b.counts[i].near_midpoint;
          for (int l = 0; l < kNumMaxLocations; ++l) {
            a.counts[i].by_location[l] += b.counts[i].by_location[l];
          }
        }
        a.mismatches += b.mismatches;
        return a;
      });
  study.counts = total.counts;
  study.class_mismatches = total.mismatches;
  return study;
}

}  // namespace tetrefine::reproduce
