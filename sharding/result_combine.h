#pragma once

// The statistics and stop reason of a sharded refinement, from those of its parts.

#include <cstdint>
#include <vector>

#include "core/mesh.h"
#include "core/refine.h"

namespace tetrefine::sharding {

// When and why refining the whole mesh stops, given its parts' results.
struct WholeStop {
  int iterations = 0;  // iterations the whole mesh completes
  StopReason reason = StopReason::kConverged;
  int64_t next_iteration_tets = 0;          // kTetBudget: tets the refused iteration needed
  double next_iteration_min_quality = 0.0;  // kQualityFloor: its worst tet
};

// Every decision of an iteration is local to an edge or a face, so the whole mesh and its parts
// refine identically tet by tet: what differs is only when each stops. The whole mesh completes
// iteration i unless
//   - every part has converged before i (kConverged, or kMinEdgeLength: Settled),
//   - i > max_iterations (kMaxIterations if some part still had an edge above epsilon, else
//     Settled),
//   - the tets after i, summed over the parts (a converged part keeps its count), exceed
//     `max_tets` (kTetBudget: the core checks the budget first),
//   - some part refused i for the quality floor (kQualityFloor; the worst tet of the whole is the
//     worst over the refusing parts).
// That is: the reason of the part that stops earliest, tet budget before quality floor, and
// max_iterations before converged. A part that refused i for the quality floor does not report
// how many tets i would have made; its count before i stands in (a lower bound), so in that
// corner the tet budget can be missed and next_iteration_tets is a lower bound.
// Parts that completed more iterations than the whole must be refined again with
// max_iterations = WholeStop::iterations before merging.
WholeStop CombineStops(const std::vector<const RefineResult*>& parts, int max_iterations,
                       int64_t max_tets);

// Why a whole mesh whose parts have all stopped splitting stopped: kMinEdgeLength when some part
// keeps an edge above epsilon for its length (the whole mesh holds that edge too), else
// kConverged.
StopReason Settled(const std::vector<const RefineResult*>& parts);

// The number of distinct edges of `mesh`.
int64_t CountEdges(const Mesh& mesh);

// The per-iteration statistics of the whole (iterations 1..`iterations`; every part has completed
// min(iterations, its own count), i.e. after CombineStops and any second round):
//   counts add (INT, FNT, NTwE, edges, split edges, short edges kept, configurations, SP);
//   max_error and quality.min take the extreme; mean_error is weighted by edges, quality.mean by
//   tets; seconds is the slowest part (parts run concurrently).
// An edge on a part boundary belongs to a tet of each side, so it is counted (and its error
// averaged) once per part: edges and split edges exceed the unsharded counts by the boundary's
// share. A part that converged before iteration i still counts in i as the unsharded run would:
// its tets unchanged (configuration 0), its final edges and errors (its short edges kept are not
// reported by the core and count as 0).
std::vector<IterationStats> CombineIterations(const std::vector<const RefineResult*>& parts,
                                              int iterations);

// The summary fields of `out` from the parts: initial and final quality, lattice statistics,
// final edge errors (max; mean weighted by each part's tets) and tets reoriented. Leaves the
// mesh, iterations and stop alone. Lattice: counts add, max takes the max, per-point means are
// weighted by points sampled, and the per-volume means by the volume each part sampled:
// `part_volumes` (each part's mesh volume) times the share of its tets sampled. Each part samples
// up to lattice_max_tets of its own tets, so a sampled lattice differs from the unsharded one;
// with every tet sampled, only summation order differs.
void CombineSummary(const std::vector<const RefineResult*>& parts,
                    const std::vector<double>& part_volumes, RefineResult* out);

}  // namespace tetrefine::sharding
