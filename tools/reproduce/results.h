#pragma once

#include <cstdint>
#include <string>
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
  double seconds = 0.0;           // wall time of the Refine call
  int64_t peak_added_bytes = -1;  // peak RSS added during the call (-1: not measurable)
  BaselineMatch uniform_at_max;   // uniform level reaching this run's lattice max error
  BaselineMatch uniform_at_mean;  // ... and its lattice mean error
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
  std::vector<RunRecord> runs;  // per epsilon: 4 iterations, then to convergence
  std::vector<BaselineLevel> uniform;
  int64_t uniform_cap_tets = 0;  // no uniform level beyond this many tets was built
};

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
  int64_t max_tets = 0;          // RefineOptions::max_tets of every run
  int64_t uniform_cap_tets = 0;  // largest uniform level built
  std::vector<CaseRecord> cases;
  std::vector<StudyRecord> study;
  std::vector<double> study_thresholds;
  int64_t study_max_tets = 0;
  std::vector<std::string> notes;  // skipped inputs, reader warnings
  double total_seconds = 0.0;
};

}  // namespace tetrefine::reproduce
