#include "wire/response_reader.h"

#include <algorithm>
#include <string_view>
#include <utility>

#include "absl/strings/str_cat.h"
#include "core/huge_pages.h"

namespace tetrefine::wire {
namespace {

absl::Status Malformed(absl::string_view what) {
  return absl::InternalError(absl::StrCat("malformed Refine response: ", what));
}

// Declared counts come from the server; reserving is an optimisation only, so a nonsensical
// count must not turn into a huge allocation. What is reserved is offered huge pages: appending
// the chunks faulted it in 4 KiB pages, 30% of the page faults of a whole `tetrefine refine`
// with the embedded service (bench/file_to_file.sh, 3.3 M tets out, 2026-11-24).
template <typename T>
void ReserveUpTo(std::vector<T>& v, int64_t count) {
  constexpr int64_t kMaxReserve = int64_t{1} << 24;
  if (count > 0) ReserveHuge(v, static_cast<size_t>(std::min(count, kMaxReserve)));
}

// Checks a chunk's start index and length against what was received and declared.
absl::Status CheckRun(absl::string_view kind, int64_t start, int64_t received, int64_t length,
                      int64_t declared) {
  if (start != received) {
    return Malformed(absl::StrCat(kind, ".start_index: expected ", received, ", got ", start));
  }
  if (length <= 0 || length > declared - received) {
    return Malformed(absl::StrCat(kind, ": ", length, " elements at ", start,
                                  " are none or run past the declared ", declared));
  }
  return absl::OkStatus();
}

}  // namespace

ResponseReader::ResponseReader(IterationCallback on_iteration, MeshCallback on_mesh,
                               bool expect_final_mesh)
    : on_iteration_(std::move(on_iteration)),
      on_mesh_(std::move(on_mesh)),
      expect_final_mesh_(expect_final_mesh) {}

absl::Status ResponseReader::Add(const v1::RefineResponse& response) {
  using R = v1::RefineResponse;
  if (complete_) return Malformed("a message after the summary");
  const bool is_chunk = response.kind_case() != R::kIterationStats &&
                        response.kind_case() != R::kMeshHeader &&
                        response.kind_case() != R::kSummary;
  if (is_chunk != header_.has_value()) {
    return Malformed(is_chunk ? "a mesh chunk without a mesh_header"
                              : "a message inside an incomplete mesh");
  }
  switch (response.kind_case()) {
    case R::kIterationStats: {
      absl::StatusOr<IterationStats> stats = IterationStatsFromWire(response.iteration_stats());
      if (!stats.ok()) return stats.status();
      if (on_iteration_) on_iteration_(*stats);
      reply_.result.iterations.push_back(*std::move(stats));
      return absl::OkStatus();
    }
    case R::kMeshHeader:
      return AddMeshHeader(response.mesh_header());
    case R::kVertexChunk: {
      const v1::VertexChunk& chunk = response.vertex_chunk();
      if (chunk.coordinates_size() % 3 != 0) {
        return Malformed("vertex_chunk.coordinates: length not a multiple of 3");
      }
      absl::Status s = CheckRun("vertex_chunk", chunk.start_index(), mesh_.points.size(),
                                chunk.coordinates_size() / 3, header_->vertex_count());
      if (!s.ok()) return s;
      for (int i = 0; i < chunk.coordinates_size(); i += 3) {
        mesh_.points.push_back(
            {chunk.coordinates(i), chunk.coordinates(i + 1), chunk.coordinates(i + 2)});
      }
      break;
    }
    case R::kValueChunk: {
      const v1::ValueChunk& chunk = response.value_chunk();
      absl::Status s = CheckRun("value_chunk", chunk.start_index(), mesh_.values.size(),
                                chunk.values_size(), header_->value_count());
      if (!s.ok()) return s;
      mesh_.values.insert(mesh_.values.end(), chunk.values().begin(), chunk.values().end());
      break;
    }
    case R::kTetChunk: {
      const v1::TetChunk& chunk = response.tet_chunk();
      if (chunk.indices_size() % 4 != 0) {
        return Malformed("tet_chunk.indices: length not a multiple of 4");
      }
      absl::Status s = CheckRun("tet_chunk", chunk.start_index(), mesh_.tets.size(),
                                chunk.indices_size() / 4, header_->tet_count());
      if (!s.ok()) return s;
      for (int i = 0; i < chunk.indices_size(); i += 4) {
        const Tet tet{chunk.indices(i), chunk.indices(i + 1), chunk.indices(i + 2),
                      chunk.indices(i + 3)};
        for (uint32_t v : tet) {
          if (static_cast<int64_t>(v) >= header_->vertex_count()) {
            return Malformed(absl::StrCat("tet_chunk.indices: vertex ", v, " out of range"));
          }
        }
        mesh_.tets.push_back(tet);
      }
      break;
    }
    case R::kTetIterationChunk: {
      const v1::TetIterationChunk& chunk = response.tet_iteration_chunk();
      absl::Status s = CheckRun("tet_iteration_chunk", chunk.start_index(), tet_iteration_.size(),
                                chunk.iterations_size(), header_->tet_iteration_count());
      if (!s.ok()) return s;
      tet_iteration_.insert(tet_iteration_.end(), chunk.iterations().begin(),
                            chunk.iterations().end());
      break;
    }
    case R::kTetQualityChunk: {
      const v1::TetQualityChunk& chunk = response.tet_quality_chunk();
      absl::Status s = CheckRun("tet_quality_chunk", chunk.start_index(), tet_quality_.size(),
                                chunk.qualities_size(), header_->tet_quality_count());
      if (!s.ok()) return s;
      tet_quality_.insert(tet_quality_.end(), chunk.qualities().begin(), chunk.qualities().end());
      break;
    }
    case R::kTetLabelChunk: {
      const v1::TetLabelChunk& chunk = response.tet_label_chunk();
      absl::Status s = CheckRun("tet_label_chunk", chunk.start_index(), mesh_.labels.size(),
                                chunk.labels_size(), header_->tet_label_count());
      if (!s.ok()) return s;
      mesh_.labels.insert(mesh_.labels.end(), chunk.labels().begin(), chunk.labels().end());
      break;
    }
    case R::kTetParentChunk: {
      const v1::TetParentChunk& chunk = response.tet_parent_chunk();
      absl::Status s = CheckRun("tet_parent_chunk", chunk.start_index(), tet_parent_.size(),
                                chunk.parents_size(), header_->tet_parent_count());
      if (!s.ok()) return s;
      tet_parent_.insert(tet_parent_.end(), chunk.parents().begin(), chunk.parents().end());
      break;
    }
    case R::kSummary:
      return AddSummary(response.summary());
    default:
      return Malformed("a message with no known kind");
  }
  FinishMeshIfComplete();
  return absl::OkStatus();
}

absl::Status ResponseReader::AddMeshHeader(const v1::ResultMeshHeader& header) {
  if (final_mesh_received_) return Malformed("a mesh after the final mesh");
  const int64_t v = header.vertex_count();
  const int64_t t = header.tet_count();
  if (v < 0 || t < 0 || (header.value_count() != 0 && header.value_count() != v) ||
      (header.tet_iteration_count() != 0 && header.tet_iteration_count() != t) ||
      (header.tet_quality_count() != 0 && header.tet_quality_count() != t) ||
      (header.tet_label_count() != 0 && header.tet_label_count() != t) ||
      (header.tet_parent_count() != 0 && header.tet_parent_count() != t)) {
    return Malformed("mesh_header: inconsistent counts");
  }
  header_ = header;
  mesh_ = Mesh{};
  tet_iteration_.clear();
  tet_quality_.clear();
  tet_parent_.clear();
  ReserveUpTo(mesh_.points, v);
  ReserveUpTo(mesh_.tets, t);
  ReserveUpTo(mesh_.values, header.value_count());
  ReserveUpTo(tet_iteration_, header.tet_iteration_count());
  ReserveUpTo(tet_quality_, header.tet_quality_count());
  ReserveUpTo(mesh_.labels, header.tet_label_count());
  ReserveUpTo(tet_parent_, header.tet_parent_count());
  FinishMeshIfComplete();
  return absl::OkStatus();
}

void ResponseReader::FinishMeshIfComplete() {
  const v1::ResultMeshHeader& h = *header_;
  if (static_cast<int64_t>(mesh_.points.size()) != h.vertex_count() ||
      static_cast<int64_t>(mesh_.values.size()) != h.value_count() ||
      static_cast<int64_t>(mesh_.tets.size()) != h.tet_count() ||
      static_cast<int64_t>(tet_iteration_.size()) != h.tet_iteration_count() ||
      static_cast<int64_t>(tet_quality_.size()) != h.tet_quality_count() ||
      static_cast<int64_t>(mesh_.labels.size()) != h.tet_label_count() ||
      static_cast<int64_t>(tet_parent_.size()) != h.tet_parent_count()) {
    return;
  }
  if (h.final()) {
    reply_.result.mesh = std::move(mesh_);
    reply_.result.tet_iteration = std::move(tet_iteration_);
    reply_.result.tet_quality = std::move(tet_quality_);
    reply_.result.tet_parent = std::move(tet_parent_);
    final_mesh_received_ = true;
  } else if (on_mesh_) {
    on_mesh_(h.iteration(), mesh_);
  }
  mesh_ = Mesh{};
  tet_iteration_ = {};
  tet_quality_ = {};
  tet_parent_ = {};
  header_.reset();
}

absl::Status ResponseReader::AddSummary(const v1::Summary& summary) {
  if (expect_final_mesh_ && !final_mesh_received_) {
    return Malformed("summary before the final mesh");
  }
  if (summary.iterations() != static_cast<int64_t>(reply_.result.iterations.size())) {
    return Malformed(absl::StrCat("summary.iterations: ", summary.iterations(), ", but ",
                                  reply_.result.iterations.size(),
                                  " iteration_stats were received"));
  }
  absl::Status s = SummaryFromWire(summary, &reply_.result, &reply_.service);
  if (!s.ok()) return s;
  complete_ = true;
  return absl::OkStatus();
}

}  // namespace tetrefine::wire
