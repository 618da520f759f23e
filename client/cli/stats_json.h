#pragma once

#include <cstdint>
#include <string>

#include "client/refine_client.h"

namespace tetrefine::cli {

// What the statistics file records about the run besides the result.
struct RunDescription {
  std::string volume_path;
  std::string mesh_path;
  std::string output_path;
  std::string backend;  // "embedded service" or "server host:port"
  client::RefineRequestOptions options;
  bool fit_mesh_to_volume = false;
  int64_t input_vertices = 0;
  int64_t input_tets = 0;
};

// The same content as the printed report, as a JSON document (see README "Command line"):
// inputs and options, one object per iteration with every IterationStats field (configurations
// keyed by the paper's names "0", "1", "2a", ...), quality before and after, lattice statistics,
// stop reason and timings.
std::string RefineStatsJson(const RunDescription& run, const client::ClientResult& reply);

}  // namespace tetrefine::cli
