#include "tools/reproduce/case_runner.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <iterator>
#include <string>
#include <utility>

#include "absl/strings/str_cat.h"
#include "bench/support/process_memory.h"
#include "core/lattice.h"
#include "core/quality.h"
#include "tools/reproduce/mesh_scores.h"
#include "tools/reproduce/schemes.h"
#include "tools/reproduce/uniform_refine.h"

namespace tetrefine::reproduce {
namespace {

using Clock = std::chrono::steady_clock;

double Since(Clock::time_point t) {
  return std::chrono::duration<double>(Clock::now() - t).count();
}

constexpr int kLatticeN = 8;
constexpr uint64_t kLatticeSeed = 1;

RunRecord RunOnce(const CaseInput& input, const Scheme& scheme, double epsilon, int max_iterations,
                  double norm, const RunOptions& options) {
  RefineOptions o;
  o.epsilon = epsilon;
  o.max_iterations = max_iterations;
  o.max_tets = options.max_tets;
  o.lattice_n = 0;  // scored below, outside the timed call
  scheme.apply(o);
  RunRecord run;
  run.scheme = scheme.name;
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
  run.certified_max_error = r->certified_max_error;
  run.lattice = SampleLattice(*input.volume, r->mesh, kLatticeN, options.lattice_max_tets,
                              kLatticeSeed, norm, epsilon, /*clamp=*/false);
  return run;
}

BaselineLevel ScoreLevel(const Volume& volume, const Mesh& mesh, int level, double norm,
                         const RunOptions& options) {
  const LatticeStats s = SampleLattice(volume, mesh, kLatticeN, options.lattice_max_tets,
                                       kLatticeSeed, norm, /*epsilon=*/1.0, /*clamp=*/false);
  const MidpointErrorStats mid = MidpointErrors(volume, mesh, norm);
  return {.level = level,
          .tets = static_cast<int64_t>(mesh.tets.size()),
          .lattice_max = s.max_error,
          .lattice_mean = s.mean_error,
          .midpoint_max = mid.max_error,
          .midpoint_mean = mid.mean_error,
          .quality = MeshQuality(mesh)};
}

MethodRow NewRow(std::string method, double epsilon) {
  MethodRow row;
  row.method = std::move(method);
  row.epsilon = epsilon;
  return row;
}

MethodRow RowOf(const RunRecord& r) {
  MethodRow row = NewRow(absl::StrCat("tetrefine ", r.scheme), r.epsilon);
  if (r.final_tets == 0) {
    row.not_run = r.stop_reason;  // the Refine call failed; its message
    return row;
  }
  row.tets = r.final_tets;
  row.rounds = static_cast<int>(r.iterations.size());
  row.midpoint_max = r.final_max_error;
  row.midpoint_mean = r.final_mean_error;
  row.lattice = r.lattice;
  row.quality = r.final_quality;
  row.stop_reason = r.stop_reason;
  row.seconds = r.seconds;
  return row;
}

// Plaza on the case at `epsilon`, scored by core like the other methods.
MethodRow PlazaRow(const CaseInput& input, const std::filesystem::path& case_dir, double epsilon,
                   double norm, const RunOptions& options) {
  MethodRow row = NewRow(kPlazaMethod, epsilon);
  if (options.plaza == nullptr) {
    row.not_run = options.plaza_not_run;
    return row;
  }
  std::fprintf(stderr, "  %s: Plaza, epsilon %.2f\n", input.name.c_str(), epsilon);
  absl::StatusOr<PlazaResult> r = RunPlaza(*options.plaza, case_dir, epsilon);
  if (!r.ok()) {
    row.not_run = absl::StrCat("failed: ", r.status().message());
    std::fprintf(stderr, "  %s\n", row.not_run.c_str());
    return row;
  }
  const Volume& volume = *input.volume;
  SampleValues(volume, r->mesh);
  row.tets = static_cast<int64_t>(r->mesh.tets.size());
  row.rounds = r->report.rounds;
  const MidpointErrorStats mid = MidpointErrors(volume, r->mesh, norm);
  row.midpoint_max = mid.max_error;
  row.midpoint_mean = mid.mean_error;
  row.lattice = SampleLattice(volume, r->mesh, kLatticeN, options.lattice_max_tets, kLatticeSeed,
                              norm, epsilon, /*clamp=*/false);
  row.quality = MeshQuality(r->mesh);
  row.stop_reason = r->report.stop_reason;
  row.seconds = r->report.seconds;
  row.has_self_report = true;
  row.self_report = r->report;
  return row;
}

// Uniform 1:8 as a method at `epsilon`: the first level whose lattice max error is at most
// epsilon ("lattice_reached"), else the last level built ("tet_cap").
MethodRow UniformRow(const CaseRecord& c, double epsilon) {
  MethodRow row = NewRow(kUniformMethod, epsilon);
  const BaselineLevel* chosen = &c.uniform.back();
  row.stop_reason = "tet_cap";
  for (const BaselineLevel& l : c.uniform) {
    if (l.lattice_max <= epsilon) {
      chosen = &l;
      row.stop_reason = "lattice_reached";
      break;
    }
  }
  row.tets = chosen->tets;
  row.rounds = chosen->level;
  row.midpoint_max = chosen->midpoint_max;
  row.midpoint_mean = chosen->midpoint_mean;
  row.lattice.n = kLatticeN;
  row.lattice.tets_sampled = chosen->tets;
  row.lattice.max_error = chosen->lattice_max;
  row.lattice.mean_error = chosen->lattice_mean;
  row.quality = chosen->quality;
  for (const BaselineLevel& l : c.uniform) {
    if (l.level <= chosen->level) row.seconds += l.seconds;
  }
  return row;
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

  std::vector<RunRecord> full;  // per epsilon, per scheme: the runs to convergence
  for (double epsilon : options.epsilons) {
    for (const Scheme& scheme : kSchemes) {
      std::vector<int> caps = {options.max_iterations};
      if (&scheme == &kPaperScheme && options.max_iterations > 4) caps.insert(caps.begin(), 4);
      for (int cap : caps) {
        std::fprintf(stderr, "  %s: %s, epsilon %.2f, up to %d iterations\n", c.name.c_str(),
                     scheme.name, epsilon, cap);
        c.runs.push_back(RunOnce(input, scheme, epsilon, cap, c.norm_coeff, options));
      }
      full.push_back(c.runs.back());
    }
  }

  std::vector<MethodRow> plaza;
  const std::filesystem::path case_dir = options.peer_dir / c.name;
  std::string export_error;
  if (options.plaza != nullptr) {
    if (absl::Status s = ExportPlazaCase(volume, input.mesh, c.norm_coeff, case_dir); !s.ok()) {
      export_error = absl::StrCat("failed: ", s.message());
    }
  }
  for (double epsilon : options.epsilons) {
    if (!export_error.empty()) {
      plaza.push_back(NewRow(kPlazaMethod, epsilon));
      plaza.back().not_run = export_error;
      continue;
    }
    plaza.push_back(PlazaRow(input, case_dir, epsilon, c.norm_coeff, options));
  }

  // Uniform levels until one matches every result on both lattice measures and reaches the
  // smallest epsilon on the lattice, or the cap.
  double target_max = 1e300, target_mean = 1e300;
  for (const RunRecord& r : c.runs) {
    if (r.final_tets == 0) continue;
    target_max = std::min(target_max, r.lattice.max_error);
    target_mean = std::min(target_mean, r.lattice.mean_error);
  }
  for (const MethodRow& p : plaza) {
    if (!p.not_run.empty()) continue;
    target_max = std::min(target_max, p.lattice.max_error);
    target_mean = std::min(target_mean, p.lattice.mean_error);
  }
  for (double epsilon : options.epsilons) target_max = std::min(target_max, epsilon);
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

  const size_t schemes = std::size(kSchemes);
  for (size_t e = 0; e < options.epsilons.size(); ++e) {
    for (size_t s = 0; s < schemes; ++s) c.methods.push_back(RowOf(full[e * schemes + s]));
    c.methods.push_back(plaza[e]);
    c.methods.push_back(UniformRow(c, options.epsilons[e]));
  }
  for (MethodRow& row : c.methods) {
    if (row.not_run.empty() && row.method != kUniformMethod) {
      row.uniform_at_max = FirstLevel(c.uniform, true, row.lattice.max_error);
    }
  }
  return c;
}

}  // namespace tetrefine::reproduce
