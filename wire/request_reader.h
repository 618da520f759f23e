#pragma once

#include <cstdint>
#include <optional>
#include <vector>

#include "absl/status/status.h"
#include "core/mesh.h"
#include "core/volume.h"
#include "tetrefine/v1/tetrefine.pb.h"
#include "wire/conversion.h"
#include "wire/service_limits.h"

namespace tetrefine::wire {

// Everything a Refine request stream carries, checked.
struct RefineInput {
  RequestOptions options;
  Volume volume;
  Mesh mesh;
};

// Assembles a Refine request stream into a RefineInput, one message at a time, checking order,
// offsets, lengths, values and limits as it goes. Declared sizes are checked against the limits
// before any storage is reserved for them.
class RequestReader {
 public:
  explicit RequestReader(const ServiceLimits& limits) : limits_(limits) {}

  // Consumes the next message. INVALID_ARGUMENT (naming the field and the index or value) or
  // RESOURCE_EXHAUSTED; after an error the reader must not be used again.
  absl::Status Add(const v1::RefineRequest& request);

  // True once end_of_input has been accepted.
  bool complete() const { return stage_ == Stage::kDone; }
  // The error for a stream that ended before end_of_input.
  absl::Status IncompleteError() const;

  int64_t bytes_received() const { return bytes_received_; }
  int64_t tets_declared() const { return tet_count_; }
  // Request messages added so far.
  int64_t messages_received() const { return message_index_; }
  // Bytes the input will occupy once assembled, as declared by the headers so far: voxel bytes
  // plus vertices and tets at their in-memory size. Grows as headers arrive; never shrinks.
  int64_t DeclaredInputBytes() const;
  // The options, once the first message has been accepted.
  const RequestOptions& options() const { return options_; }

  // The assembled input; only after complete(). Leaves the reader empty.
  RefineInput Take();

 private:
  enum class Stage { kOptions, kVolumeHeader, kVolumeData, kMeshHeader, kMeshData, kDone };

  absl::Status AddOptions(const v1::RefineOptions& options);
  absl::Status AddVolumeHeader(const v1::VolumeHeader& header);
  absl::Status AddVolumeChunk(const v1::VolumeChunk& chunk);
  absl::Status AddMeshHeader(const v1::MeshHeader& header);
  absl::Status AddVertexChunk(const v1::VertexChunk& chunk);
  absl::Status AddTetChunk(const v1::TetChunk& chunk);
  absl::Status AddTetLabelChunk(const v1::TetLabelChunk& chunk);
  absl::Status AddEndOfInput();
  absl::Status Unexpected(const v1::RefineRequest& request) const;

  ServiceLimits limits_;
  Stage stage_ = Stage::kOptions;
  int64_t message_index_ = 0;  // of the message being added, for error messages
  int64_t bytes_received_ = 0;

  RequestOptions options_;
  GridGeometry grid_;
  Index3 lo_{0, 0, 0};
  Index3 hi_{0, 0, 0};
  VoxelType voxel_type_ = VoxelType::kFloat64;
  uint64_t total_bytes_ = 0;
  std::vector<std::byte> volume_data_;
  std::optional<Volume> volume_;

  int64_t vertex_count_ = 0;
  int64_t tet_count_ = 0;
  bool has_labels_ = false;
  Mesh mesh_;
};

}  // namespace tetrefine::wire
