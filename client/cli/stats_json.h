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
  // > 0: the result was written as that many .pvtu pieces, never merged. output_mesh then counts
  // `piece_vertices`, the vertices summed over the pieces (a vertex on the boundary between two
  // pieces is in both), and says how many pieces.
  int output_pieces = 0;
  int64_t piece_vertices = 0;
};

// The same content as the printed report, as a JSON document (see README "Command line"):
// inputs and options, one object per iteration with every IterationStats field (configurations
// keyed by the paper's names "0", "1", "2a", ...), quality before and after, lattice statistics,
// stop reason and timings.
std::string RefineStatsJson(const RunDescription& run, const client::ClientResult& reply);

}  // namespace tetrefine::cli
