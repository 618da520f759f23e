#pragma once

// What `tetrefine plot` needs from the JSON that `tetrefine refine --stats-json` writes
// (stats_json.cc): per iteration the tets and the largest edge-midpoint error, epsilon, the
// scheme and why the run stopped.

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "absl/status/statusor.h"

namespace tetrefine::cli {

struct ConvergenceRun {
  std::string scheme;    // options.scheme; empty when absent
  bool certify = false;  // options.certify; false when absent
  // certified_max_error is a number: the run was asked to certify and did (certify converged).
  bool certified = false;
  // options.norm_coeff: what the errors are relative to when the run was given one; unset (null
  // or absent) means the volume's value range.
  std::optional<double> norm_coeff;
  std::string stop_reason;  // empty when absent
  double epsilon = 0.0;     // options.epsilon, > 0
  // Index i is iteration i: 0 is the input (iterations[0].initial_tets, or input.tets when no
  // iteration ran), i >= 1 the mesh after
  // iteration i (iterations[i - 1].final_tets).
  std::vector<int64_t> tets;
  // The largest edge-midpoint error of those meshes: iteration i's is measured at the start of
  // iteration i + 1 (iterations[i].max_error); the last mesh's is final_max_error. That one is
  // left out (error is one shorter than tets) when the file has none or the run was cancelled
  // (then it may belong to an earlier mesh).
  std::vector<double> max_error;
};

// Parses the JSON text. Errors name the missing or wrong field ("iterations[2].final_tets:
// expected a whole number >= 0") or the JSON syntax error with its line and column, and the
// fields that contradict each other, as no run of refine writes them: an error below 0, an
// iteration numbered out of turn, an iteration that does not start from the tets the one before
// ended with, or output_mesh.tets other than the last iteration's (or, with no iteration, the
// input's). With an empty `iterations` array (a run that stopped before its first iteration)
// the input mesh is the one point: `tets` is {input.tets}. The caller prefixes the file name.
absl::StatusOr<ConvergenceRun> ParseConvergenceRun(std::string_view json_text);

// Reads and parses the file at `path`; every error starts with the path.
absl::StatusOr<ConvergenceRun> ReadConvergenceRun(const std::string& path);

}  // namespace tetrefine::cli
