#pragma once

#include <cstdint>
#include <functional>
#include <optional>
#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "core/mesh.h"
#include "core/refine.h"
#include "tetrefine/v1/tetrefine.pb.h"
#include "wire/conversion.h"

namespace tetrefine::wire {

// A Refine call's answer: the core result as core Refine would have returned it, plus what
// only the service knows.
struct RefineReply {
  RefineResult result;
  ServiceSummary service;
};

// Reassembles a Refine response stream. Checks what it relies on, so a broken or hostile server
// yields an error rather than a crash.
class ResponseReader {
 public:
  using IterationCallback = std::function<void(const IterationStats&)>;
  using MeshCallback = std::function<void(int iteration, const Mesh& mesh)>;

  // Callbacks may be empty. `expect_final_mesh`: false when skip_final_mesh was requested.
  ResponseReader(IterationCallback on_iteration, MeshCallback on_mesh, bool expect_final_mesh);

  // Consumes the next message; INTERNAL naming the field for a malformed stream.
  absl::Status Add(const v1::RefineResponse& response);

  // True once the summary has been accepted.
  bool complete() const { return complete_; }

  // The assembled reply; only after complete().
  RefineReply Take() { return std::move(reply_); }

 private:
  absl::Status AddMeshHeader(const v1::ResultMeshHeader& header);
  absl::Status AddSummary(const v1::Summary& summary);
  // Hands over the current mesh once every declared element has arrived.
  void FinishMeshIfComplete();

  IterationCallback on_iteration_;
  MeshCallback on_mesh_;
  bool expect_final_mesh_;
  bool complete_ = false;
  bool final_mesh_received_ = false;

  std::optional<v1::ResultMeshHeader> header_;  // of the mesh being received
  Mesh mesh_;
  std::vector<int32_t> tet_iteration_;
  std::vector<float> tet_quality_;
  std::vector<uint32_t> tet_parent_;

  RefineReply reply_;
};

}  // namespace tetrefine::wire
