#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "core/refine.h"
#include "tools/reproduce/max_location_study.h"

namespace tetrefine::reproduce {

// A uniform-refinement level's size and lattice error (all tets sampled, n = 8).
struct BaselineLevel {
  int level = 0;  // 0: the input mesh
  int64_t tets = 0;
  double lattice_max = 0.0;
  double lattice_mean = 0.0;
  double midpoint_max = 0.0;  // edge-midpoint error (eq. 3) over the level's unique edges
  double midpoint_mean = 0.0;
  QualityStats quality;
  double seconds = 0.0;  // refining to this level from the previous one
};

// The first uniform level whose lattice error is at most a tetrefine result's.
struct BaselineMatch {
  bool reached = false;
  int level = -1;
  int64_t tets = 0;
};

// One Refine call on a case.
struct RunRecord {
  std::string scheme;  // a name from schemes.h
  double epsilon = 0.0;
  int max_iterations = 0;
  std::string stop_reason;
  std::vector<IterationStats> iterations;
  int64_t initial_tets = 0;
  int64_t final_tets = 0;
  QualityStats initial_quality;
  QualityStats final_quality;
  LatticeStats lattice;
  double final_max_error = 0.0;  // edge-midpoint error of the returned mesh
  double final_mean_error = 0.0;
  double certified_max_error = -1.0;  // RefineResult's (certified runs that converged), else < 0
  double seconds = 0.0;               // wall time of the Refine call
  int64_t peak_added_bytes = -1;      // peak RSS added during the call (-1: not measurable)
  BaselineMatch uniform_at_max;       // uniform level reaching this run's lattice max error
  BaselineMatch uniform_at_mean;      // ... and its lattice mean error
};

// What a peer's own script said about its run: its counts and timing, and its own scores of the
// result, kept to check that the peer scores the way core does (the report uses core's).
struct PeerSelfReport {
  std::string version;  // e.g. "DOLFINx 0.5.2"
  int rounds = 0;
  std::string stop_reason;
  double seconds = 0.0;        // the refinement rounds (marks and refinement), one process
  double setup_seconds = 0.0;  // building the peer's mesh from the input arrays
  int64_t tets = 0;
  double midpoint_max = 0.0;
  double lattice_max = 0.0;
  double lattice_mean = 0.0;
  double quality_min = 0.0;
  double quality_mean = 0.0;
};

// The names of the methods that are not tetrefine schemes ("tetrefine <scheme>").
inline constexpr char kPlazaMethod[] = "Plaza (DOLFINx)";
inline constexpr char kUniformMethod[] = "uniform 1:8";

// One method's result on a case at one epsilon, scored the same way whatever the method: the
// midpoint error over the result's unique edges, core SampleLattice (n = 8, every tet up to
// RunOptions::lattice_max_tets), mean-ratio quality over every tet.
struct MethodRow {
  std::string method;  // "tetrefine <scheme>", "Plaza (DOLFINx)", "uniform 1:8"
  double epsilon = 0.0;
  std::string not_run;  // why there are no figures (e.g. "python3-dolfinx missing"); "" if run
  int64_t tets = 0;
  int rounds = 0;  // tetrefine iterations, Plaza rounds, uniform levels
  double midpoint_max = 0.0;
  double midpoint_mean = 0.0;
  LatticeStats lattice;
  QualityStats quality;
  std::string stop_reason;
  double seconds = 0.0;
  // The first uniform level whose lattice max error is at most this row's (not for uniform).
  BaselineMatch uniform_at_max;
  bool has_self_report = false;  // peers: their own account, see PeerSelfReport
  PeerSelfReport self_report;
};

struct CaseRecord {
  std::string name;         // identifier, also the plot's file name
  std::string volume_name;  // e.g. "epi_brain_58x58x24" or "heart1 phantom"
  std::string mesh_kind;    // "5-tet blocks", "unstructured cube", "shell"
  std::string description;  // how volume and mesh were made (markdown)
  std::array<int64_t, 3> dims{};
  std::array<double, 3> spacing{};
  std::string voxel_type;
  double norm_coeff = 0.0;
  int64_t input_vertices = 0;
  int64_t input_tets = 0;
  // Per epsilon: the paper scheme for 4 iterations, then every scheme to convergence.
  std::vector<RunRecord> runs;
  std::vector<BaselineLevel> uniform;
  int64_t uniform_cap_tets = 0;  // no uniform level beyond this many tets was built
  // Per epsilon (in RunOptions order): each tetrefine scheme's run to convergence, Plaza, then
  // uniform 1:8 at the first level whose lattice max error is at most epsilon.
  std::vector<MethodRow> methods;
};

// A scheme's runs to convergence, one per epsilon in run order: for each epsilon, the last run
// of that scheme (the paper scheme's 4-iteration run comes before its run to convergence).
inline std::vector<const RunRecord*> RunsToConvergence(const CaseRecord& c,
                                                       std::string_view scheme) {
  std::vector<const RunRecord*> out;
  for (const RunRecord& r : c.runs) {
    if (r.scheme != scheme) continue;
    if (!out.empty() && out.back()->epsilon == r.epsilon) {
      out.back() = &r;
    } else {
      out.push_back(&r);
    }
  }
  return out;
}

struct StudyRecord {
  std::string mesh;  // e.g. "epi_brain_58x58x24, voxel 5-tet"
  std::string kind;  // "voxel-aligned" or "coarse"
  LocationStudy study;
};

struct ReportData {
  std::string generated_at;  // UTC, ISO 8601
  std::string command;
  bool quick = false;
  int hardware_threads = 0;
  std::vector<double> epsilons;
  int max_iterations = 0;
  int64_t max_tets = 0;              // RefineOptions::max_tets of every run
  int64_t uniform_cap_tets = 0;      // largest uniform level built
  std::vector<std::string> schemes;  // tetrefine schemes run, schemes.h order
  std::string plaza_status;          // "DOLFINx 0.5.2", or why Plaza was not run
  std::vector<CaseRecord> cases;
  std::vector<StudyRecord> study;
  std::vector<double> study_thresholds;
  int64_t study_max_tets = 0;
  std::vector<std::string> notes;  // skipped inputs, reader warnings
  double total_seconds = 0.0;
};

}  // namespace tetrefine::reproduce
