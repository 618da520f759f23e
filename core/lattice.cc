#include "core/lattice.h"

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "core/lattice_kernel.h"
#include "core/parallel.h"

namespace tetrefine {

MaxLocation LatticeLocation(int n, const std::array<int, 4>& ijkl) {
  int zeros = 0, halves = 0;
  for (int c : ijkl) {
    zeros += c == 0;
    halves += 2 * c == n;
  }
  if (zeros == 3) return MaxLocation::kVertex;
  if (zeros == 2) return halves == 2 ? MaxLocation::kEdgeMidpoint : MaxLocation::kEdge;
  if (zeros == 1) return MaxLocation::kFace;
  return MaxLocation::kInterior;
}

namespace {

TetLattice OneTet(const Volume& volume, const Mesh& mesh, int64_t t,
                  const lattice_internal::LatticePoints& points, double norm_coeff,
                  double epsilon) {
  const Tet& tet = mesh.tets[t];
  return lattice_internal::ScanTetLattice(
      volume, points,
      {mesh.points[tet[0]], mesh.points[tet[1]], mesh.points[tet[2]], mesh.points[tet[3]]},
      {mesh.values[tet[0]], mesh.values[tet[1]], mesh.values[tet[2]], mesh.values[tet[3]]},
      norm_coeff, epsilon);
}

// Tet t's statistics from `known` when it has them (KnownTetLattices: no point above epsilon, so
// none counted), else sampled.
TetLattice KnownOrSampled(const Volume& volume, const Mesh& mesh, int64_t t,
                          const lattice_internal::LatticePoints& points, double norm_coeff,
                          double epsilon, const KnownTetLattices& known) {
  if (known.sum_error != nullptr && !std::isnan((*known.sum_error)[t])) {
    TetLattice r;
    r.max_error = (*known.max_error)[t];
    r.sum_error = (*known.sum_error)[t];
    r.points = points.size();
    return r;
  }
  return OneTet(volume, mesh, t, points, norm_coeff, epsilon);
}

}  // namespace

// `clamp` changes nothing here or in SampleLattice (sampling clamps to the grid's box anyway, see
// LatticeErrors) but stays in the signatures: it says what the caller's refinement did.
TetLattice SampleTetLattice(const Volume& volume, const Mesh& mesh, int64_t t, int n,
                            double norm_coeff, double epsilon, bool /*clamp*/) {
  return OneTet(volume, mesh, t, lattice_internal::LatticePoints(n, /*with_corners=*/true),
                norm_coeff, epsilon);
}

LatticeStats SampleLattice(const Volume& volume, const Mesh& mesh, int n, int64_t max_tets,
                           uint64_t seed, double norm_coeff, double epsilon, bool /*clamp*/,
                           const std::function<bool()>& should_stop,
                           const KnownTetLattices& known) {
  LatticeStats stats;
  stats.n = n;
  const int64_t num_tets = static_cast<int64_t>(mesh.tets.size());
  if (n <= 0 || num_tets == 0) return stats;
  std::vector<int64_t> chosen;
  const bool sample = max_tets > 0 && num_tets > max_tets;
  if (sample) {
    std::mt19937_64 rng(seed);
    std::uniform_int_distribution<int64_t> pick(0, num_tets - 1);
    chosen.resize(max_tets);
    for (auto& c : chosen) c = pick(rng);
    std::sort(chosen.begin(), chosen.end());
  }
  const int64_t count = sample ? max_tets : num_tets;
  const int64_t blocks = BlockCount(count);
  struct Partial {
    TetLattice sums;
    double volume = 0.0, weighted_mean = 0.0, weighted_above = 0.0;
  };
  std::vector<Partial> partial(blocks);
  const lattice_internal::LatticePoints points(n, /*with_corners=*/true);
  const int64_t points_per_tet = points.size();
  const int64_t poll_every = std::max<int64_t>(1, 16384 / points_per_tet);
  ForEachBlock(count, [&](int64_t block, int64_t begin, int64_t end) {
    Partial acc;
    TetLattice r;
    for (int64_t i = begin; i < end; ++i) {
      if (should_stop && (i - begin) % poll_every == 0 && should_stop()) break;
      const int64_t t = sample ? chosen[i] : i;
      // The sample is drawn with replacement and sorted: a tet drawn again (about one draw in
      // 12 for 200 000 of 1.15 M tets) counts again with the statistics it just had.
      if (i == begin || t != (sample ? chosen[i - 1] : i - 1)) {
        r = KnownOrSampled(volume, mesh, t, points, norm_coeff, epsilon, known);
      }
      acc.sums.max_error = std::max(acc.sums.max_error, r.max_error);
      acc.sums.sum_error += r.sum_error;
      acc.sums.points += r.points;
      acc.sums.above_epsilon += r.above_epsilon;
      const Tet& q = mesh.tets[t];
      const double v = std::abs(SignedVolume6(mesh.points[q[0]], mesh.points[q[1]],
                                              mesh.points[q[2]], mesh.points[q[3]]));
      const double points = static_cast<double>(r.points);
      acc.volume += v;
      acc.weighted_mean += v * r.sum_error / points;
      acc.weighted_above += v * static_cast<double>(r.above_epsilon) / points;
    }
    partial[block] = acc;
  });
  double sum = 0.0, volume_sum = 0.0, weighted_mean = 0.0, weighted_above = 0.0;
  int64_t above = 0;
  for (const auto& p : partial) {
    stats.max_error = std::max(stats.max_error, p.sums.max_error);
    sum += p.sums.sum_error;
    stats.points_sampled += p.sums.points;
    above += p.sums.above_epsilon;
    volume_sum += p.volume;
    weighted_mean += p.weighted_mean;
    weighted_above += p.weighted_above;
  }
  if (volume_sum > 0.0) {
    stats.volume_mean_error = weighted_mean / volume_sum;
    stats.volume_share_above_epsilon = weighted_above / volume_sum;
  }
  stats.tets_sampled = count;
  if (stats.points_sampled > 0) {
    stats.mean_error = sum / static_cast<double>(stats.points_sampled);
    stats.share_above_epsilon =
        static_cast<double>(above) / static_cast<double>(stats.points_sampled);
  }
  return stats;
}

}  // namespace tetrefine
