#pragma once

#include <string>
#include <vector>

#include "absl/status/status.h"

namespace tetrefine::io {

// One dataset of a ParaView collection: the file (a .vtu) shown at `timestep`. For a refinement
// series the timestep is the iteration number.
struct PvdEntry {
  double timestep = 0;
  std::string file;  // path of the dataset; written relative to the .pvd's directory
  int part = 0;      // piece number, for several files at one timestep
};

// The text of a .pvd collection (VTKFile type="Collection") listing `entries` in order, with
// file names relative to `pvd_directory` where they lie beneath it (ParaView resolves them
// against the .pvd's own directory, so the series moves with its folder).
std::string FormatPvd(const std::vector<PvdEntry>& entries, const std::string& pvd_directory);

// Writes the collection to `path` (atomically, as WriteMesh does). Opening it in ParaView shows
// the datasets as a time series.
absl::Status WritePvd(const std::string& path, const std::vector<PvdEntry>& entries);

}  // namespace tetrefine::io
