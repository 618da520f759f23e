#pragma once

#include <filesystem>
#include <string>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "core/mesh.h"
#include "core/volume.h"
#include "tools/reproduce/results.h"

namespace tetrefine::reproduce {

// DOLFINx's Plaza refinement driven by the same edge-midpoint marks as tetrefine, run by
// bench/peers/plaza_refine.py under Debian's python3-dolfinx in a child process. The case goes to
// the script as files (volume.npy, case.json, mesh.vtu: see the script's doc) and the refined mesh
// comes back as a .vtu, which the caller scores with core like every other method's result.
struct PlazaPeer {
  std::string python = "/usr/bin/python3";  // the interpreter python3-dolfinx is installed for
  std::string script;                       // bench/peers/plaza_refine.py
  int max_rounds = 32;
  int64_t max_tets = 2'000'000;  // a round that would exceed it is discarded (tet_budget)
};

// OK when `python script --check` says python3-dolfinx imports; otherwise the reason, e.g.
// "python3-dolfinx missing" (the report prints it where the figures would be).
absl::Status CheckPlaza(const PlazaPeer& peer);

// Writes the script's input for a case into `dir` (created): the volume's samples, its grid and
// normalisation, and the mesh (without values). Errors name the file.
absl::Status ExportPlazaCase(const Volume& volume, const Mesh& mesh, double norm_coeff,
                             const std::filesystem::path& dir);

// The refined mesh (values not set) and what the script said about its run.
struct PlazaResult {
  Mesh mesh;
  PeerSelfReport report;
};

// Runs the script on an exported case directory at `epsilon`; its result files go next to the
// case as plaza_eps<epsilon>.json / .vtu. Errors say what failed (exit status, unreadable output).
absl::StatusOr<PlazaResult> RunPlaza(const PlazaPeer& peer, const std::filesystem::path& case_dir,
                                     double epsilon);

}  // namespace tetrefine::reproduce
