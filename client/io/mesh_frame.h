#pragma once

#include "absl/strings/string_view.h"
#include "client/io/mesh_file.h"

namespace tetrefine::io {

// +1 or -1: multiplying RAS coordinate `axis` (0, 1, 2) by it gives the coordinate a file in
// `frame` stores (LPS negates x and y). Applying it twice gives the input back bit for bit.
inline double FrameSign(MeshFrame frame, int axis) {
  return frame == MeshFrame::kLps && axis < 2 ? -1.0 : 1.0;
}

// Converts file.mesh.points from the stored frame (file.frame) to RAS in place.
void FrameToRas(MeshFile& file);

// The frame named in free text, as 3D Slicer writes it into a legacy VTK header ("3D Slicer
// output. SPACE=LPS"): SPACE=LPS or SPACE=RAS anywhere in `text`; kUntagged otherwise.
MeshFrame FrameFromHeader(absl::string_view text);

}  // namespace tetrefine::io
