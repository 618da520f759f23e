#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <span>

#include "core/mesh.h"
#include "core/refine.h"
#include "tetrefine/v1/tetrefine.pb.h"
#include "wire/conversion.h"

namespace tetrefine::wire {

// Receives each response message in order; returns false to stop (stream broken).
using ResponseSink = std::function<bool(const v1::RefineResponse&)>;

// Turns core results into Refine response messages. Each method returns false as soon as the
// sink does.
class ResponseWriter {
 public:
  // `chunk_bytes`: the client's hint (0: default), clamped to the protocol's bounds.
  ResponseWriter(size_t chunk_bytes, ResponseSink sink);

  bool WriteIterationStats(const IterationStats& stats);
  // A result_mesh_header and the mesh's chunks (its labels too, when it has them). The per-tet
  // arrays may be empty (intermediate meshes have none; tet_parent only when asked for).
  bool WriteMesh(int iteration, bool final, const Mesh& mesh,
                 std::span<const int32_t> tet_iteration, std::span<const float> tet_quality,
                 std::span<const uint32_t> tet_parent = {});
  bool WriteSummary(const RefineResult& result, const ServiceSummary& service, int64_t input_tets);

 private:
  size_t chunk_bytes_;
  ResponseSink sink_;
  v1::RefineResponse response_;  // reused: keeps the repeated fields' capacity
};

}  // namespace tetrefine::wire
