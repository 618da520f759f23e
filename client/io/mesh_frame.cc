#include "client/io/mesh_frame.h"

#include "absl/strings/match.h"

namespace tetrefine::io {

void FrameToRas(MeshFile& file) {
  if (file.frame != MeshFrame::kLps) return;
  for (Vec3& p : file.mesh.points) {
    p[0] = -p[0];
    p[1] = -p[1];
  }
}

MeshFrame FrameFromHeader(absl::string_view text) {
  // Slicer checks RAS first; a header naming both is contradictory either way.
  if (absl::StrContains(text, "SPACE=RAS")) return MeshFrame::kRas;
  if (absl::StrContains(text, "SPACE=LPS")) return MeshFrame::kLps;
  return MeshFrame::kUntagged;
}

}  // namespace tetrefine::io
