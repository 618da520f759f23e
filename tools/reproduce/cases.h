#pragma once

#include <memory>
#include <string>
#include <vector>

#include "core/mesh.h"
#include "core/volume.h"

namespace tetrefine::reproduce {

// A volume and an immersed mesh to refine.
struct CaseInput {
  std::string name;
  std::string volume_name;
  std::string mesh_kind;
  std::string description;
  std::shared_ptr<const Volume> volume;
  Mesh mesh;  // no values: Refine samples them
};

// A mesh for the section 5.1 study.
struct StudyInput {
  std::string label;
  std::string kind;  // "voxel-aligned" or "coarse"
  std::shared_ptr<const Volume> volume;
  Mesh mesh;
};

struct Inputs {
  std::vector<CaseInput> cases;
  std::vector<StudyInput> study;
  std::vector<std::string> notes;  // inputs skipped, reader warnings
};

struct InputOptions {
  std::string data_dir;  // holds the real volumes and unit_cube_1782tets.mesh
  bool quick = false;    // two tiny generated cases only (no files read)
};

// The cases of the reproduction:
//  - each real volume in data_dir with a coarse masked 5-tet block mesh (case_meshes.h) and with
//    the unstructured unit cube mesh fitted into its box (5% margin);
//  - the heart phantom on the paper's two SPECT grids with one shell mesh (phantoms.h);
//  - the Marschner-Lobb signal on 41^3 with a 5-tet block mesh (blocks of 4^3 voxels) and the
//    cube mesh.
// A missing file skips its cases with a note. The study gets, per volume, the voxel-aligned
// 5-tet mesh (masked like the blocks) and each case's coarse mesh.
Inputs BuildInputs(const InputOptions& options);

}  // namespace tetrefine::reproduce
