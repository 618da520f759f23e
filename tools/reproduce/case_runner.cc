#include "tools/reproduce/case_runner.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <string>

#include "bench/support/process_memory.h"
#include "core/lattice.h"
#include "core/quality.h"
#include "tools/reproduce/uniform_refine.h"

namespace tetrefine::reproduce {
namespace {

using Clock = std::chrono::steady_clock;

double Since(Clock::time_point t) {
  return std::chrono::duration<double>(Clock::now() - t).count();
}

constexpr int kLatticeN = 8;
constexpr uint64_t kLatticeSeed = 1;

QualityStats MeshQuality(const Mesh& m) {
  QualityStats q;
  q.min = 1.0;
  double sum = 0.0;
  for (const Tet& t : m.tets) {
    const double eta = MeanRatio(m.points[t[0]], m.points[t[1]], m.points[t[2]], m.points[t[3]]);
    q.min = std::min(q.min, eta);
    sum += eta;
  }
  q.count = static_cast<int64_t>(m.tets.size());
  q.mean = m.tets.empty() ? 0.0 : sum / static_cast<double>(q.count);
  return q;
}

RunRecord RunOnce(const CaseInput& input, double epsilon, int max_iterations, double norm,
                  const RunOptions& options) {
  RefineOptions o;
  o.epsilon = epsilon;
  o.max_iterations = max_iterations;
  o.max_tets = options.max_tets;
  o.lattice_n = 0;  // scored below, outside the timed call
  RunRecord run;
  run.epsilon = epsilon;
  run.max_iterations = max_iterations;
  absl::StatusOr<RefineResult> r;
  {
    bench::PeakMemoryScope memory;
    const auto start = Clock::now();
    r = Refine(*input.volume, input.mesh, o);
    run.seconds = Since(start);
    run.peak_added_bytes = memory.AddedPeakBytes();
  }
  if (!r.ok()) {
    run.stop_reason = std::string("error: ") + std::string(r.status().message());
    return run;
  }
  run.stop_reason = std::string(StopReasonName(r->stop_reason));
  run.iterations = r->iterations;
  run.initial_tets = static_cast<int64_t>(input.mesh.tets.size());
  run.final_tets = static_cast<int64_t>(r->mesh.tets.size());
  run.initial_quality = r->initial_quality;
  run.final_quality = r->final_quality;
  run.final_max_error = r->final_max_error;
  run.final_mean_error = r->final_mean_error;
  run.lattice = SampleLattice(*input.volume, r->mesh, kLatticeN, options.lattice_max_tets,
                              kLatticeSeed, norm, epsilon, /*clamp=*/false);
  return run;
}

BaselineLevel ScoreLevel(const Volume& volume, const Mesh& mesh, int level, double norm,
                         const RunOptions& options) {
  const LatticeStats s = SampleLattice(volume, mesh, kLatticeN, options.lattice_max_tets,
                                       kLatticeSeed, norm, /*epsilon=*/1.0, /*clamp=*/false);
  return {.level = level,
          .tets = static_cast<int64_t>(mesh.tets.size()),
          .lattice_max = s.max_error,
          .lattice_mean = s.mean_error,
          .quality = MeshQuality(mesh)};
}

BaselineMatch FirstLevel(const std::vector<BaselineLevel>& levels, bool by_max, double target) {
  for (const BaselineLevel& l : levels) {
    if ((by_max ? l.lattice_max : l.lattice_mean) <= target) {
      return {.reached = true, .level = l.level, .tets = l.tets};
    }
  }
  return {};
}

}  // namespace

CaseRecord RunCase(const CaseInput& input, const RunOptions& options) {
  CaseRecord c;
  c.name = input.name;
  c.volume_name = input.volume_name;
  c.mesh_kind = input.mesh_kind;
  c.description = input.description;
  const Volume& volume = *input.volume;
  for (int a = 0; a < 3; ++a) {
    c.dims[a] = volume.grid().dims[a];
    c.spacing[a] = volume.grid().spacing[a];
  }
  c.voxel_type = std::string(VoxelTypeName(volume.type()));
  const auto [lo, hi] = volume.ValueRange();
  c.norm_coeff = hi > lo ? hi - lo : 1.0;  // Refine's default normalisation
  c.input_vertices = static_cast<int64_t>(input.mesh.points.size());
  c.input_tets = static_cast<int64_t>(input.mesh.tets.size());
  c.uniform_cap_tets = options.uniform_cap_tets;

  std::vector<int> caps = {options.max_iterations};
  if (options.max_iterations > 4) caps.insert(caps.begin(), 4);
  for (double epsilon : options.epsilons) {
    for (int cap : caps) {
      std::fprintf(stderr, "  %s: epsilon %.2f, up to %d iterations\n", c.name.c_str(), epsilon,
                   cap);
      c.runs.push_back(RunOnce(input, epsilon, cap, c.norm_coeff, options));
    }
  }

  // Uniform levels until one matches every run on both lattice measures, or the cap.
  double target_max = 1e300, target_mean = 1e300;
  for (const RunRecord& r : c.runs) {
    if (r.final_tets == 0) continue;
    target_max = std::min(target_max, r.lattice.max_error);
    target_mean = std::min(target_mean, r.lattice.mean_error);
  }
  Mesh level = input.mesh;
  SampleValues(volume, level);
  c.uniform.push_back(ScoreLevel(volume, level, 0, c.norm_coeff, options));
  while (
      (c.uniform.back().lattice_max > target_max || c.uniform.back().lattice_mean > target_mean) &&
      static_cast<int64_t>(level.tets.size()) * 8 <= options.uniform_cap_tets) {
    const auto start = Clock::now();
    level = UniformRefine(volume, level);
    const double seconds = Since(start);
    std::fprintf(stderr, "  %s: uniform level %zu, %zu tets\n", c.name.c_str(), c.uniform.size(),
                 level.tets.size());
    c.uniform.push_back(
        ScoreLevel(volume, level, static_cast<int>(c.uniform.size()), c.norm_coeff, options));
    c.uniform.back().seconds = seconds;
  }
  for (RunRecord& r : c.runs) {
    if (r.final_tets == 0) continue;
    r.uniform_at_max = FirstLevel(c.uniform, true, r.lattice.max_error);
    r.uniform_at_mean = FirstLevel(c.uniform, false, r.lattice.mean_error);
  }
  return c;
}

}  // namespace tetrefine::reproduce
