#include "wire/response_writer.h"

#include <algorithm>
#include <utility>

namespace tetrefine::wire {
namespace {

size_t ClampChunkBytes(size_t hint) {
  if (hint == 0) return kDefaultChunkBytes;
  return std::clamp(hint, kMinResponseChunkBytes, kMaxChunkBytes);
}

// Splits `count` elements of `element_bytes` into runs of at most `chunk_bytes` (at least one
// element each) and calls fill(start, end) for each, stopping when it returns false.
template <typename Fill>
bool ForEachChunk(size_t count, size_t element_bytes, size_t chunk_bytes, Fill fill) {
  const size_t step = std::max<size_t>(1, chunk_bytes / element_bytes);
  for (size_t start = 0; start < count; start += step) {
    if (!fill(start, std::min(count, start + step))) return false;
  }
  return true;
}

}  // namespace

ResponseWriter::ResponseWriter(size_t chunk_bytes, ResponseSink sink)
    : chunk_bytes_(ClampChunkBytes(chunk_bytes)), sink_(std::move(sink)) {}

bool ResponseWriter::WriteIterationStats(const IterationStats& stats) {
  response_.Clear();
  IterationStatsToWire(stats, response_.mutable_iteration_stats());
  return sink_(response_);
}

bool ResponseWriter::WriteMesh(int iteration, bool final, const Mesh& mesh,
                               std::span<const int32_t> tet_iteration,
                               std::span<const float> tet_quality,
                               std::span<const uint32_t> tet_parent) {
  response_.Clear();
  v1::ResultMeshHeader* header = response_.mutable_mesh_header();
  header->set_iteration(iteration);
  header->set_final(final);
  header->set_vertex_count(static_cast<int64_t>(mesh.points.size()));
  header->set_tet_count(static_cast<int64_t>(mesh.tets.size()));
  header->set_value_count(static_cast<int64_t>(mesh.values.size()));
  header->set_tet_iteration_count(static_cast<int64_t>(tet_iteration.size()));
  header->set_tet_quality_count(static_cast<int64_t>(tet_quality.size()));
  header->set_tet_label_count(static_cast<int64_t>(mesh.labels.size()));
  header->set_tet_parent_count(static_cast<int64_t>(tet_parent.size()));
  if (!sink_(response_)) return false;

  const bool ok =
      ForEachChunk(mesh.points.size(), 3 * sizeof(double), chunk_bytes_,
                   [&](size_t start, size_t end) {
                     response_.Clear();
                     v1::VertexChunk* chunk = response_.mutable_vertex_chunk();
                     chunk->set_start_index(static_cast<int64_t>(start));
                     auto* coordinates = chunk->mutable_coordinates();
                     coordinates->Reserve(static_cast<int>(3 * (end - start)));
                     for (size_t v = start; v < end; ++v) {
                       for (double c : mesh.points[v]) coordinates->AddAlreadyReserved(c);
                     }
                     return sink_(response_);
                   }) &&
      ForEachChunk(mesh.values.size(), sizeof(double), chunk_bytes_,
                   [&](size_t start, size_t end) {
                     response_.Clear();
                     v1::ValueChunk* chunk = response_.mutable_value_chunk();
                     chunk->set_start_index(static_cast<int64_t>(start));
                     chunk->mutable_values()->Assign(mesh.values.begin() + start,
                                                     mesh.values.begin() + end);
                     return sink_(response_);
                   }) &&
      ForEachChunk(mesh.tets.size(), 4 * sizeof(uint32_t), chunk_bytes_,
                   [&](size_t start, size_t end) {
                     response_.Clear();
                     v1::TetChunk* chunk = response_.mutable_tet_chunk();
                     chunk->set_start_index(static_cast<int64_t>(start));
                     auto* indices = chunk->mutable_indices();
                     indices->Reserve(static_cast<int>(4 * (end - start)));
                     for (size_t t = start; t < end; ++t) {
                       for (uint32_t i : mesh.tets[t]) indices->AddAlreadyReserved(i);
                     }
                     return sink_(response_);
                   }) &&
      ForEachChunk(tet_iteration.size(), sizeof(int32_t), chunk_bytes_,
                   [&](size_t start, size_t end) {
                     response_.Clear();
                     v1::TetIterationChunk* chunk = response_.mutable_tet_iteration_chunk();
                     chunk->set_start_index(static_cast<int64_t>(start));
                     chunk->mutable_iterations()->Assign(tet_iteration.begin() + start,
                                                         tet_iteration.begin() + end);
                     return sink_(response_);
                   }) &&
      ForEachChunk(tet_quality.size(), sizeof(float), chunk_bytes_,
                   [&](size_t start, size_t end) {
                     response_.Clear();
                     v1::TetQualityChunk* chunk = response_.mutable_tet_quality_chunk();
                     chunk->set_start_index(static_cast<int64_t>(start));
                     chunk->mutable_qualities()->Assign(tet_quality.begin() + start,
                                                        tet_quality.begin() + end);
                     return sink_(response_);
                   }) &&
      ForEachChunk(mesh.labels.size(), LabelWireBytes(mesh.labels), chunk_bytes_,
                   [&](size_t start, size_t end) {
                     response_.Clear();
                     v1::TetLabelChunk* chunk = response_.mutable_tet_label_chunk();
                     chunk->set_start_index(static_cast<int64_t>(start));
                     chunk->mutable_labels()->Assign(mesh.labels.begin() + start,
                                                     mesh.labels.begin() + end);
                     return sink_(response_);
                   }) &&
      ForEachChunk(
          tet_parent.size(), sizeof(uint32_t), chunk_bytes_, [&](size_t start, size_t end) {
            response_.Clear();
            v1::TetParentChunk* chunk = response_.mutable_tet_parent_chunk();
            chunk->set_start_index(static_cast<int64_t>(start));
            chunk->mutable_parents()->Assign(tet_parent.begin() + start, tet_parent.begin() + end);
            return sink_(response_);
          });
  return ok;
}

bool ResponseWriter::WriteSummary(const RefineResult& result, const ServiceSummary& service,
                                  int64_t input_tets) {
  response_.Clear();
  SummaryToWire(result, service, input_tets, response_.mutable_summary());
  return sink_(response_);
}

}  // namespace tetrefine::wire
