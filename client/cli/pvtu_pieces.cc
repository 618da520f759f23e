#include "client/cli/pvtu_pieces.h"

#include <utility>

#include "sharding/mesh_partition.h"

namespace tetrefine::cli {

std::vector<io::MeshFile> CutIntoPieces(const io::MeshFile& file, int pieces) {
  std::vector<sharding::MeshPart> parts =
      sharding::ExtractParts(file.mesh, sharding::PartitionTets(file.mesh, pieces));
  std::vector<io::MeshFile> out;
  out.reserve(parts.size());
  for (sharding::MeshPart& part : parts) {
    io::MeshFile piece{.mesh = std::move(part.mesh), .tet_iteration = {}, .tet_quality = {}};
    piece.label_name = file.label_name;
    piece.frame = file.frame;
    for (uint32_t t : part.input_tet) {
      if (!file.tet_iteration.empty()) piece.tet_iteration.push_back(file.tet_iteration[t]);
      if (!file.tet_quality.empty()) piece.tet_quality.push_back(file.tet_quality[t]);
    }
    out.push_back(std::move(piece));
  }
  return out;
}

}  // namespace tetrefine::cli
