#pragma once

#include <cstddef>
#include <functional>

#include "core/mesh.h"
#include "core/volume.h"
#include "tetrefine/v1/tetrefine.pb.h"
#include "wire/conversion.h"

namespace tetrefine::wire {

// Receives each request message in protocol order; returns false to stop (stream broken).
using RequestSink = std::function<bool(const v1::RefineRequest&)>;

// Emits a whole Refine request stream: options, the volume (or slab) in chunks of `chunk_bytes`
// payload bytes (at least one element a chunk), the mesh's points and tets likewise (not its
// values: the server samples the volume), then end_of_input.
// Returns false as soon as `sink` does.
bool WriteRequest(const RequestOptions& options, const Volume& volume, const Mesh& mesh,
                  size_t chunk_bytes, const RequestSink& sink);

}  // namespace tetrefine::wire
