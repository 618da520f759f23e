#pragma once

#include <cstdint>
#include <map>
#include <string>

#include "client/io/mesh_file.h"

namespace tetrefine::io::iotest {

// The system interpreter, which has Debian's meshio, VTK and numpy (a venv's python may not).
inline constexpr char kPython[] = "/usr/bin/python3";

// A fresh directory under the test temp dir, removed (with its contents) on destruction.
class ScratchDir {
 public:
  ScratchDir();
  ~ScratchDir();
  ScratchDir(const ScratchDir&) = delete;
  ScratchDir& operator=(const ScratchDir&) = delete;

  // path() + "/" + name.
  std::string File(const std::string& name) const;
  const std::string& path() const { return path_; }

 private:
  std::string path_;
};

// Writes `bytes` to `path` verbatim (test fixtures, corrupt files); aborts the test on failure.
void WriteBytes(const std::string& path, const std::string& bytes);
std::string ReadBytes(const std::string& path);

// A random mesh with `vertices` points (coordinates of mixed sign and magnitude, from 1e-300 to
// 1e12) and `tets` tetrahedra with distinct in-range indices. Optional arrays are filled when
// asked, with awkward values (negative, huge, tiny, non-terminating binary fractions).
struct RandomMeshOptions {
  int vertices = 50;
  int tets = 80;
  bool values = true;
  bool iteration = true;
  bool quality = true;
  bool labels = false;  // mesh.labels: small region numbers, some negative, zero or extreme
  std::string label_name = "region";
  MeshFrame frame = MeshFrame::kUntagged;
};
MeshFile RandomMesh(uint64_t seed, const RandomMeshOptions& options = {});

// Path of a file in the shared real-data directory.
std::string SharedData(const std::string& name);

// Path of a fixture in tests/data/meshes.
std::string MeshFixture(const std::string& name);

// The volume of each region of `file` (its labels, which it must have), from signed tet volumes.
std::map<int32_t, double> RegionVolumes(const MeshFile& file);

}  // namespace tetrefine::io::iotest
