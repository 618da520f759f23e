#include "wire/request_writer.h"

#include <algorithm>
#include <cstdint>

namespace tetrefine::wire {
namespace {

void SetIndex(const Index3& i, v1::GridIndex* out) {
  out->set_x(i[0]);
  out->set_y(i[1]);
  out->set_z(i[2]);
}

void SetVector(const Vec3& v, v1::Vector3* out) {
  out->set_x(v[0]);
  out->set_y(v[1]);
  out->set_z(v[2]);
}

// Elements of `element_bytes` each that fit `chunk_bytes`, at least one.
size_t PerChunk(size_t chunk_bytes, size_t element_bytes) {
  return std::max<size_t>(1, chunk_bytes / element_bytes);
}

bool WriteVolume(const Volume& volume, size_t chunk_bytes, const RequestSink& sink) {
  v1::RefineRequest request;
  v1::VolumeHeader* header = request.mutable_volume_header();
  SetIndex(volume.grid().dims, header->mutable_dims());
  SetVector(volume.grid().origin, header->mutable_origin());
  SetVector(volume.grid().spacing, header->mutable_spacing());
  SetIndex(volume.lo(), header->mutable_slab_lo());
  SetIndex(volume.hi(), header->mutable_slab_hi());
  header->set_voxel_type(VoxelTypeToWire(volume.type()));
  // The identity travels as the empty list, so axis-aligned requests stay byte-identical.
  if (!volume.axis_aligned()) {
    for (double d : volume.grid().direction) header->add_direction(d);
  }
  const std::vector<std::byte>& data = volume.data();
  header->set_total_bytes(data.size());
  if (!sink(request)) return false;

  const size_t step = PerChunk(chunk_bytes, 1);
  for (size_t offset = 0; offset < data.size(); offset += step) {
    const size_t n = std::min(step, data.size() - offset);
    request.Clear();
    v1::VolumeChunk* chunk = request.mutable_volume_chunk();
    chunk->set_offset(offset);
    chunk->set_data(reinterpret_cast<const char*>(data.data()) + offset, n);
    if (!sink(request)) return false;
  }
  return true;
}

bool WriteMesh(const Mesh& mesh, size_t chunk_bytes, const RequestSink& sink) {
  v1::RefineRequest request;
  v1::MeshHeader* header = request.mutable_mesh_header();
  header->set_vertex_count(static_cast<int64_t>(mesh.points.size()));
  header->set_tet_count(static_cast<int64_t>(mesh.tets.size()));
  // Values are never sent: the server samples the volume at every vertex (tetrefine.proto,
  // MeshHeader.has_values). Labels are sent when the mesh has them; the server checks their count.
  const bool has_labels = !mesh.labels.empty();
  header->set_has_labels(has_labels);
  if (!sink(request)) return false;

  const size_t vertex_step = PerChunk(chunk_bytes, 3 * sizeof(double));
  for (size_t start = 0; start < mesh.points.size(); start += vertex_step) {
    const size_t end = std::min(mesh.points.size(), start + vertex_step);
    request.Clear();
    v1::VertexChunk* chunk = request.mutable_vertex_chunk();
    chunk->set_start_index(static_cast<int64_t>(start));
    chunk->mutable_coordinates()->Reserve(static_cast<int>(3 * (end - start)));
    for (size_t v = start; v < end; ++v) {
      for (double c : mesh.points[v]) chunk->add_coordinates(c);
    }
    if (!sink(request)) return false;
  }
  const size_t tet_step = PerChunk(chunk_bytes, 4 * sizeof(uint32_t));
  for (size_t start = 0; start < mesh.tets.size(); start += tet_step) {
    const size_t end = std::min(mesh.tets.size(), start + tet_step);
    request.Clear();
    v1::TetChunk* chunk = request.mutable_tet_chunk();
    chunk->set_start_index(static_cast<int64_t>(start));
    chunk->mutable_indices()->Reserve(static_cast<int>(4 * (end - start)));
    for (size_t t = start; t < end; ++t) {
      for (uint32_t i : mesh.tets[t]) chunk->add_indices(i);
    }
    if (!sink(request)) return false;
  }
  if (!has_labels) return true;
  const size_t label_step = PerChunk(chunk_bytes, LabelWireBytes(mesh.labels));
  for (size_t start = 0; start < mesh.labels.size(); start += label_step) {
    const size_t end = std::min(mesh.labels.size(), start + label_step);
    request.Clear();
    v1::TetLabelChunk* chunk = request.mutable_tet_label_chunk();
    chunk->set_start_index(static_cast<int64_t>(start));
    chunk->mutable_labels()->Add(mesh.labels.begin() + static_cast<std::ptrdiff_t>(start),
                                 mesh.labels.begin() + static_cast<std::ptrdiff_t>(end));
    if (!sink(request)) return false;
  }
  return true;
}

}  // namespace

bool WriteRequest(const RequestOptions& options, const Volume& volume, const Mesh& mesh,
                  size_t chunk_bytes, const RequestSink& sink) {
  chunk_bytes = std::min(chunk_bytes, kMaxChunkBytes);
  v1::RefineRequest request;
  RequestOptionsToWire(options, request.mutable_options());
  if (!sink(request)) return false;
  if (!WriteVolume(volume, chunk_bytes, sink)) return false;
  if (!WriteMesh(mesh, chunk_bytes, sink)) return false;
  request.Clear();
  request.mutable_end_of_input();
  return sink(request);
}

}  // namespace tetrefine::wire
