#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "tools/reproduce/cases.h"
#include "tools/reproduce/plaza_peer.h"
#include "tools/reproduce/results.h"

namespace tetrefine::reproduce {

struct RunOptions {
  std::vector<double> epsilons{0.10, 0.05};
  // Iterations (tetrefine) and rounds (Plaza) of a run "to convergence"; the paper scheme also
  // runs 4 iterations per epsilon for the paper's four-iteration tables.
  int max_iterations = 32;
  int64_t max_tets = 2'000'000;
  // Lattice statistics sample every tet of meshes up to this size (a seeded sample beyond).
  int64_t lattice_max_tets = 3'000'000;
  // No uniform level with more tets than this is built.
  int64_t uniform_cap_tets = 3'000'000;
  // Plaza runs when set; otherwise every Plaza row says "not run: " + plaza_not_run.
  const PlazaPeer* plaza = nullptr;
  std::string plaza_not_run;
  std::filesystem::path peer_dir;  // Plaza's case directories go to peer_dir / case name
};

// Refines the case with every scheme of schemes.h at every epsilon (to convergence; the paper
// scheme first for 4 iterations), with Plaza, and uniformly until a level's lattice max and mean
// error are at most every result's and its max at most the smallest epsilon (or the cap). Every
// result is scored on the n = 8 lattice; CaseRecord::methods lines the methods up per epsilon.
// Wall time and peak memory cover the Refine call only; peak memory is measured in this
// long-running process (process_memory.h: a lower bound).
CaseRecord RunCase(const CaseInput& input, const RunOptions& options);

}  // namespace tetrefine::reproduce
