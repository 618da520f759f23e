#include "wire/request_reader.h"

#include <array>
#include <cmath>
#include <cstring>
#include <limits>
#include <new>
#include <string>
#include <utility>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"

namespace tetrefine::wire {
namespace {

// The core's own bound on samples per axis (core/volume.cc), checked here so that a header the
// core would refuse is answered before its data is uploaded. It also keeps per-axis arithmetic
// on indices far from overflow.
constexpr int64_t kMaxDim = int64_t{1} << 20;

std::string KindName(const v1::RefineRequest& request) {
  const google::protobuf::FieldDescriptor* field =
      v1::RefineRequest::descriptor()->FindFieldByNumber(request.kind_case());
  return field != nullptr ? field->name() : "nothing (no known kind set)";
}

absl::Status Invalid(std::string message) { return absl::InvalidArgumentError(message); }

constexpr const char* kAxis[3] = {"x", "y", "z"};

Index3 IndexFromWire(const v1::GridIndex& i) { return {i.x(), i.y(), i.z()}; }
Vec3 VectorFromWire(const v1::Vector3& v) { return {v.x(), v.y(), v.z()}; }

// Reads volume_header.direction into *direction: empty is the identity; otherwise 9 finite values
// (row-major) whose normalised columns have |det| >= kMinDirectionDeterminant, the core's bound,
// checked here so a bad header is refused before its data is uploaded.
absl::Status DirectionFromWire(const v1::VolumeHeader& header, Mat3* direction) {
  const int n = header.direction_size();
  if (n == 0) {
    *direction = kIdentityDirection;
    return absl::OkStatus();
  }
  if (n != 9) {
    return Invalid(
        absl::StrCat("volume_header.direction: must hold 0 (identity) or 9 values "
                     "(3x3 row-major), got ",
                     n));
  }
  for (int i = 0; i < 9; ++i) (*direction)[i] = header.direction(i);
  switch (const DirectionDefect defect = FindDirectionDefect(*direction); defect.kind) {
    case DirectionDefect::Kind::kNone:
      break;
    case DirectionDefect::Kind::kNotFinite:
      return Invalid(absl::StrCat("volume_header.direction[", defect.index,
                                  "]: must be finite, got ", header.direction(defect.index)));
    case DirectionDefect::Kind::kZeroColumn:
      return Invalid(absl::StrCat("volume_header.direction: column ", defect.index,
                                  " is zero (or overflows), so the matrix is singular"));
    case DirectionDefect::Kind::kSingular:
      return Invalid(
          absl::StrCat("volume_header.direction: singular (|det| of the normalised "
                       "columns is ",
                       defect.det, ", must be >= ", kMinDirectionDeterminant, ")"));
  }
  // The protocol's columns are unit vectors and the voxel size is `spacing`. Core would take a
  // scaled column as a scale, so the likely mistake, direction = affine[:3, :3] sent with
  // spacing = the voxel sizes, refined a volume scaled twice without a word (found 2026-11-28 by
  // a review of the Python client). 1e-3 accepts directions typed with four digits (0.7071)
  // and refuses any voxel size that differs from 1 by more than that.
  constexpr double kUnitTolerance = 1e-3;
  for (int c = 0; c < 3; ++c) {
    const double length = std::hypot((*direction)[c], (*direction)[3 + c], (*direction)[6 + c]);
    if (!(std::abs(length - 1.0) <= kUnitTolerance)) {
      return Invalid(absl::StrCat(
          "volume_header.direction: column ", c, " has length ", length,
          "; the columns are unit vectors and the voxel size goes in volume_header.spacing "
          "(from an affine: its 3x3 part with each column divided by that column's length)"));
    }
  }
  return absl::OkStatus();
}

}  // namespace

absl::Status RequestReader::Add(const v1::RefineRequest& request) {
  bytes_received_ += static_cast<int64_t>(request.ByteSizeLong());
  absl::Status status;
  using R = v1::RefineRequest;
  switch (stage_) {
    case Stage::kOptions:
      status =
          request.kind_case() == R::kOptions ? AddOptions(request.options()) : Unexpected(request);
      break;
    case Stage::kVolumeHeader:
      status = request.kind_case() == R::kVolumeHeader ? AddVolumeHeader(request.volume_header())
                                                       : Unexpected(request);
      break;
    case Stage::kVolumeData:
      status = request.kind_case() == R::kVolumeChunk ? AddVolumeChunk(request.volume_chunk())
                                                      : Unexpected(request);
      break;
    case Stage::kMeshHeader:
      status = request.kind_case() == R::kMeshHeader ? AddMeshHeader(request.mesh_header())
                                                     : Unexpected(request);
      break;
    case Stage::kMeshData:
      switch (request.kind_case()) {
        case R::kVertexChunk:
          status = AddVertexChunk(request.vertex_chunk());
          break;
        case R::kTetChunk:
          status = AddTetChunk(request.tet_chunk());
          break;
        case R::kTetLabelChunk:
          status = AddTetLabelChunk(request.tet_label_chunk());
          break;
        case R::kEndOfInput:
          status = AddEndOfInput();
          break;
        case R::kValueChunk:
          status = Invalid(absl::StrCat(
              "request message ", message_index_,
              ": value_chunk not accepted: this server samples every vertex value from the "
              "volume (client values are not used)"));
          break;
        default:
          status = Unexpected(request);
      }
      break;
    case Stage::kDone:
      status = Unexpected(request);
      break;
  }
  ++message_index_;
  return status;
}

absl::Status RequestReader::Unexpected(const v1::RefineRequest& request) const {
  std::string expected;
  switch (stage_) {
    case Stage::kOptions:
      expected = "options (it must come first)";
      break;
    case Stage::kVolumeHeader:
      expected = "volume_header";
      break;
    case Stage::kVolumeData:
      expected = absl::StrCat("volume_chunk (", total_bytes_ - volume_data_.size(),
                              " of volume_header.total_bytes = ", total_bytes_, " still missing)");
      break;
    case Stage::kMeshHeader:
      expected = "mesh_header";
      break;
    case Stage::kMeshData:
      expected = has_labels_ ? "vertex_chunk, tet_chunk, tet_label_chunk or end_of_input"
                             : "vertex_chunk, tet_chunk or end_of_input";
      break;
    case Stage::kDone:
      expected = "nothing after end_of_input";
      break;
  }
  return Invalid(absl::StrCat("request message ", message_index_, ": expected ", expected, ", got ",
                              KindName(request)));
}

absl::Status RequestReader::IncompleteError() const {
  // gRPC reports a message that does not parse as a RefineRequest exactly like the end of the
  // stream, so the error names both causes.
  const std::string or_garbage =
      absl::StrCat("or request message ", message_index_, " did not parse as a RefineRequest)");
  switch (stage_) {
    case Stage::kOptions:
      return Invalid(
          absl::StrCat("options: missing (the stream ended before any options, ", or_garbage));
    case Stage::kVolumeHeader:
      return Invalid(
          absl::StrCat("volume_header: missing (the stream ended after options, ", or_garbage));
    case Stage::kVolumeData:
      return Invalid(absl::StrCat("volume_chunk: stream ended after ", volume_data_.size(),
                                  " of volume_header.total_bytes = ", total_bytes_, " bytes (",
                                  or_garbage));
    case Stage::kMeshHeader:
      return Invalid(
          absl::StrCat("mesh_header: missing (the stream ended after the volume, ", or_garbage));
    case Stage::kMeshData:
      return Invalid(
          absl::StrCat("end_of_input: missing (the stream ended inside the mesh, ", or_garbage));
    case Stage::kDone:
      break;
  }
  return absl::OkStatus();
}

absl::Status RequestReader::AddOptions(const v1::RefineOptions& options) {
  absl::StatusOr<RequestOptions> parsed = RequestOptionsFromWire(options, limits_);
  if (!parsed.ok()) return parsed.status();
  options_ = *std::move(parsed);
  stage_ = Stage::kVolumeHeader;
  return absl::OkStatus();
}

absl::Status RequestReader::AddVolumeHeader(const v1::VolumeHeader& header) {
  if (!header.has_dims()) return Invalid("volume_header.dims: missing");
  grid_.dims = IndexFromWire(header.dims());
  grid_.origin = VectorFromWire(header.origin());
  grid_.spacing = header.has_spacing() ? VectorFromWire(header.spacing()) : Vec3{1.0, 1.0, 1.0};
  lo_ = header.has_slab_lo() ? IndexFromWire(header.slab_lo()) : Index3{0, 0, 0};
  hi_ = header.has_slab_hi() ? IndexFromWire(header.slab_hi()) : grid_.dims;
  for (int a = 0; a < 3; ++a) {
    if (grid_.dims[a] < 2 || grid_.dims[a] > kMaxDim) {
      return Invalid(absl::StrCat("volume_header.dims.", kAxis[a], ": must be in [2, ", kMaxDim,
                                  "], got ", grid_.dims[a]));
    }
    if (!std::isfinite(grid_.origin[a])) {
      return Invalid(absl::StrCat("volume_header.origin.", kAxis[a], ": must be finite, got ",
                                  grid_.origin[a]));
    }
    // Below the smallest normal double the inverse overflows (core's Volume::Create says why).
    if (!(grid_.spacing[a] >= std::numeric_limits<double>::min()) ||
        !std::isfinite(grid_.spacing[a])) {
      return Invalid(absl::StrCat("volume_header.spacing.", kAxis[a],
                                  ": must be finite and > 0 (at least ",
                                  std::numeric_limits<double>::min(), "), got ", grid_.spacing[a]));
    }
    if (lo_[a] < 0 || lo_[a] >= grid_.dims[a]) {
      return Invalid(absl::StrCat("volume_header.slab_lo.", kAxis[a], ": must be in [0, ",
                                  grid_.dims[a], "), got ", lo_[a]));
    }
    if (hi_[a] <= lo_[a] || hi_[a] > grid_.dims[a]) {
      return Invalid(absl::StrCat("volume_header.slab_hi.", kAxis[a], ": must be in (", lo_[a],
                                  ", ", grid_.dims[a], "], got ", hi_[a]));
    }
  }
  absl::Status direction = DirectionFromWire(header, &grid_.direction);
  if (!direction.ok()) return direction;
  absl::StatusOr<VoxelType> type =
      VoxelTypeFromWire(header.voxel_type(), "volume_header.voxel_type");
  if (!type.ok()) return type.status();
  voxel_type_ = *type;

  // Extents are <= 2^31 each, so each partial product below stays far from overflow as long as
  // it is checked against the limit before the next multiplication.
  int64_t voxels = 1;
  for (int a = 0; a < 3; ++a) {
    voxels *= hi_[a] - lo_[a];
    if (voxels > limits_.max_voxels) {
      return absl::ResourceExhaustedError(
          absl::StrCat("volume_header: the slab [", lo_[0], ",", lo_[1], ",", lo_[2], ") - [",
                       hi_[0], ",", hi_[1], ",", hi_[2], ") has more than this server's limit of ",
                       limits_.max_voxels, " voxels (--max_voxels)"));
    }
  }
  const uint64_t expected = static_cast<uint64_t>(voxels) * VoxelSize(voxel_type_);
  if (header.total_bytes() != expected) {
    return Invalid(absl::StrCat("volume_header.total_bytes: expected ", expected, " (", voxels,
                                " voxels of ", std::string(VoxelTypeName(voxel_type_)), "), got ",
                                header.total_bytes()));
  }
  total_bytes_ = expected;
  // Reserved up front so that a large volume is not copied as it grows. A declared size within
  // the limits that this process still cannot hold (a memory-limited container) is refused here,
  // not thrown out of the handler as an UNKNOWN error.
  try {
    volume_data_.reserve(total_bytes_);
  } catch (const std::bad_alloc&) {
    return absl::ResourceExhaustedError(absl::StrCat(
        "volume_header: this server cannot allocate the ", total_bytes_, " bytes declared"));
  }
  stage_ = Stage::kVolumeData;
  return absl::OkStatus();
}

absl::Status RequestReader::AddVolumeChunk(const v1::VolumeChunk& chunk) {
  const uint64_t received = volume_data_.size();
  if (chunk.offset() != received) {
    return Invalid(absl::StrCat("volume_chunk.offset: expected ", received,
                                " (the bytes received so far), got ", chunk.offset()));
  }
  if (chunk.data().empty()) {
    return Invalid(absl::StrCat("volume_chunk.data: empty at offset ", chunk.offset()));
  }
  if (chunk.data().size() > total_bytes_ - received) {
    return Invalid(absl::StrCat("volume_chunk.data: ", chunk.data().size(), " bytes at offset ",
                                chunk.offset(),
                                " run past volume_header.total_bytes = ", total_bytes_));
  }
  const auto* bytes = reinterpret_cast<const std::byte*>(chunk.data().data());
  volume_data_.insert(volume_data_.end(), bytes, bytes + chunk.data().size());
  if (volume_data_.size() < total_bytes_) return absl::OkStatus();

  absl::StatusOr<Volume> volume =
      Volume::Create(grid_, lo_, hi_, voxel_type_, std::move(volume_data_));
  volume_data_ = {};
  if (!volume.ok()) return volume.status();
  volume_ = *std::move(volume);
  if (options_.refine.norm_coeff.has_value()) {
    absl::Status norm = CheckNormCoeffForRange(*options_.refine.norm_coeff, volume_->ValueRange());
    if (!norm.ok()) return norm;
  }
  stage_ = Stage::kMeshHeader;
  return absl::OkStatus();
}

absl::Status RequestReader::AddMeshHeader(const v1::MeshHeader& header) {
  vertex_count_ = header.vertex_count();
  tet_count_ = header.tet_count();
  if (tet_count_ < 0) {
    return Invalid(absl::StrCat("mesh_header.tet_count: must be >= 0, got ", tet_count_));
  }
  if (vertex_count_ < 0) {
    return Invalid(absl::StrCat("mesh_header.vertex_count: must be >= 0, got ", vertex_count_));
  }
  if (tet_count_ > limits_.max_input_tets) {
    return absl::ResourceExhaustedError(
        absl::StrCat("mesh_header.tet_count: ", tet_count_, " exceeds this server's limit of ",
                     limits_.max_input_tets, " input tets (--max_input_tets)"));
  }
  // Checked here, before the tets are received, rather than left to the core.
  if (tet_count_ > ToCoreOptions(options_, limits_).max_tets) {
    if (options_.send_max_tets) {
      return Invalid(absl::StrCat("mesh_header.tet_count: ", tet_count_,
                                  " exceeds options.max_tets = ", options_.refine.max_tets));
    }
    return absl::ResourceExhaustedError(
        absl::StrCat("mesh_header.tet_count: ", tet_count_, " exceeds this server's limit of ",
                     limits_.max_output_tets, " output tets (--max_output_tets)"));
  }
  // A mesh needs at most 4 vertices a tet; more would be memory spent on nothing.
  const int64_t max_vertices = 4 * limits_.max_input_tets;
  if (vertex_count_ > max_vertices) {
    return absl::ResourceExhaustedError(absl::StrCat(
        "mesh_header.vertex_count: ", vertex_count_, " exceeds this server's limit of ",
        max_vertices, " input vertices (4 x --max_input_tets)"));
  }
  if (header.has_values()) {
    return Invalid(
        "mesh_header.has_values: must be false: this server samples every vertex value from the "
        "volume (client values are not used), so send no value_chunk");
  }
  has_labels_ = header.has_labels();
  try {  // as for the volume
    mesh_.points.reserve(static_cast<size_t>(vertex_count_));
    mesh_.tets.reserve(static_cast<size_t>(tet_count_));
    if (has_labels_) mesh_.labels.reserve(static_cast<size_t>(tet_count_));
  } catch (const std::bad_alloc&) {
    mesh_ = Mesh{};
    return absl::ResourceExhaustedError(absl::StrCat("mesh_header: this server cannot allocate ",
                                                     vertex_count_, " vertices and ", tet_count_,
                                                     " tets"));
  }
  stage_ = Stage::kMeshData;
  return absl::OkStatus();
}

absl::Status RequestReader::AddVertexChunk(const v1::VertexChunk& chunk) {
  const int64_t received = static_cast<int64_t>(mesh_.points.size());
  if (chunk.start_index() != received) {
    return Invalid(absl::StrCat("vertex_chunk.start_index: expected ", received,
                                " (the vertices received so far), got ", chunk.start_index()));
  }
  const int size = chunk.coordinates_size();
  if (size == 0 || size % 3 != 0) {
    return Invalid(
        absl::StrCat("vertex_chunk.coordinates: length must be a positive multiple "
                     "of 3, got ",
                     size, " at start_index ", chunk.start_index()));
  }
  if (size / 3 > vertex_count_ - received) {
    return Invalid(absl::StrCat("vertex_chunk.coordinates: ", size / 3, " vertices at start_index ",
                                chunk.start_index(),
                                " run past mesh_header.vertex_count = ", vertex_count_));
  }
  for (int i = 0; i < size; i += 3) {
    const Vec3 p{chunk.coordinates(i), chunk.coordinates(i + 1), chunk.coordinates(i + 2)};
    for (int a = 0; a < 3; ++a) {
      if (!std::isfinite(p[a])) {
        return Invalid(absl::StrCat("vertex_chunk.coordinates: vertex ", received + i / 3,
                                    " has a non-finite ", kAxis[a], " coordinate (", p[a], ")"));
      }
    }
    mesh_.points.push_back(p);
  }
  return absl::OkStatus();
}

absl::Status RequestReader::AddTetChunk(const v1::TetChunk& chunk) {
  const int64_t received = static_cast<int64_t>(mesh_.tets.size());
  if (chunk.start_index() != received) {
    return Invalid(absl::StrCat("tet_chunk.start_index: expected ", received,
                                " (the tets received so far), got ", chunk.start_index()));
  }
  const int size = chunk.indices_size();
  if (size == 0 || size % 4 != 0) {
    return Invalid(
        absl::StrCat("tet_chunk.indices: length must be a positive multiple of 4, "
                     "got ",
                     size, " at start_index ", chunk.start_index()));
  }
  if (size / 4 > tet_count_ - received) {
    return Invalid(absl::StrCat("tet_chunk.indices: ", size / 4, " tets at start_index ",
                                chunk.start_index(),
                                " run past mesh_header.tet_count = ", tet_count_));
  }
  for (int i = 0; i < size; i += 4) {
    Tet tet;
    for (int c = 0; c < 4; ++c) {
      tet[c] = chunk.indices(i + c);
      if (static_cast<int64_t>(tet[c]) >= vertex_count_) {
        return Invalid(absl::StrCat("tet_chunk.indices: tet ", received + i / 4, " corner ", c,
                                    " is vertex ", tet[c], ", out of range for ",
                                    "mesh_header.vertex_count = ", vertex_count_));
      }
    }
    mesh_.tets.push_back(tet);
  }
  return absl::OkStatus();
}

absl::Status RequestReader::AddTetLabelChunk(const v1::TetLabelChunk& chunk) {
  if (!has_labels_) {
    return Invalid(absl::StrCat("request message ", message_index_,
                                ": tet_label_chunk without mesh_header.has_labels"));
  }
  const int64_t received = static_cast<int64_t>(mesh_.labels.size());
  if (chunk.start_index() != received) {
    return Invalid(absl::StrCat("tet_label_chunk.start_index: expected ", received,
                                " (the labels received so far), got ", chunk.start_index()));
  }
  const int size = chunk.labels_size();
  if (size == 0) {
    return Invalid(
        absl::StrCat("tet_label_chunk.labels: empty at start_index ", chunk.start_index()));
  }
  if (size > tet_count_ - received) {
    return Invalid(absl::StrCat("tet_label_chunk.labels: ", size, " labels at start_index ",
                                chunk.start_index(),
                                " run past mesh_header.tet_count = ", tet_count_));
  }
  mesh_.labels.insert(mesh_.labels.end(), chunk.labels().begin(), chunk.labels().end());
  return absl::OkStatus();
}

absl::Status RequestReader::AddEndOfInput() {
  if (static_cast<int64_t>(mesh_.points.size()) != vertex_count_) {
    return Invalid(absl::StrCat("vertex_chunk: received ", mesh_.points.size(),
                                " vertices, mesh_header.vertex_count = ", vertex_count_));
  }
  if (static_cast<int64_t>(mesh_.tets.size()) != tet_count_) {
    return Invalid(absl::StrCat("tet_chunk: received ", mesh_.tets.size(),
                                " tets, mesh_header.tet_count = ", tet_count_));
  }
  if (has_labels_ && static_cast<int64_t>(mesh_.labels.size()) != tet_count_) {
    return Invalid(absl::StrCat("tet_label_chunk: received ", mesh_.labels.size(),
                                " labels, mesh_header.tet_count = ", tet_count_,
                                " (mesh_header.has_labels)"));
  }
  stage_ = Stage::kDone;
  return absl::OkStatus();
}

int64_t RequestReader::DeclaredInputBytes() const {
  return static_cast<int64_t>(total_bytes_) + vertex_count_ * static_cast<int64_t>(sizeof(Vec3)) +
         tet_count_ * static_cast<int64_t>(sizeof(Tet) + (has_labels_ ? sizeof(int32_t) : 0));
}

RefineInput RequestReader::Take() {
  return RefineInput{.options = options_, .volume = *std::move(volume_), .mesh = std::move(mesh_)};
}

}  // namespace tetrefine::wire
