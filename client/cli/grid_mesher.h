#pragma once

#include <cstdint>
#include <optional>

#include "absl/status/statusor.h"
#include "core/mesh.h"
#include "core/volume.h"

namespace tetrefine::cli {

struct GridMeshOptions {
  // Cells of block x block x block voxels become one hexahedral cell of the mesh. Per axis the
  // cell boundaries are the samples 0, block, 2 block, ... and the last sample, so a last, thinner
  // cell covers what remains and the mesh always spans the whole grid.
  int64_t block = 1;
  // Set: keep only the cells whose 8 corner samples are all >= the threshold (the paper's liver
  // set-up tetrahedrizes the voxels inside the organ). Unset: every cell.
  std::optional<double> mask_threshold;
  // Refuse grids that would make more tets than this.
  int64_t max_tets = 50'000'000;
};

struct GridMesh {
  Mesh mesh;          // values: the volume's samples at the vertices (exact, they sit on samples)
  int64_t cells = 0;  // cells of the grid
  int64_t cells_kept = 0;  // cells meshed (all, without a threshold)
};

// Five positively oriented tets per cell. Neighbouring cells alternate between the two mirror
// images of the 5-tet split (by the parity of the cell index), so both sides of a shared square
// face cut it along the same diagonal and the mesh is conformal. Only the vertices some tet uses
// are kept. Errors: no cell kept, block < 1, or too many tets.
absl::StatusOr<GridMesh> MeshVolumeGrid(const Volume& volume, const GridMeshOptions& options);

}  // namespace tetrefine::cli
