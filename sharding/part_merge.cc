#include "sharding/part_merge.h"

#include <array>
#include <bit>
#include <limits>

#include "absl/container/flat_hash_map.h"
#include "absl/status/status.h"
#include "absl/strings/str_cat.h"
#include "sharding/point_key.h"

namespace tetrefine::sharding {
namespace {

bool InAnotherBox(const Vec3& p, const std::vector<MeshPart>& parts, size_t self) {
  for (size_t q = 0; q < parts.size(); ++q) {
    if (q != self && InBox(p, parts[q].box_lo, parts[q].box_hi)) return true;
  }
  return false;
}

// Appends to `out` the input tet of each of part `p`'s tet parents (indices into the part's
// tets, as its server returned them). INTERNAL if one is not a tet of the part.
absl::Status AppendInputParents(int p, const MeshPart& part, const std::vector<uint32_t>& parents,
                                std::vector<uint32_t>& out) {
  out.reserve(out.size() + parents.size());
  for (uint32_t parent : parents) {
    if (parent >= part.input_tet.size()) {
      return absl::InternalError(
          absl::StrCat("part ", p, ": tet parent ", parent, " is not a tet of the part sent"));
    }
    out.push_back(part.input_tet[parent]);
  }
  return absl::OkStatus();
}

}  // namespace

absl::StatusOr<RefinedMesh> PieceOfPart(int p, const MeshPart& part, RefineResult& refined) {
  RefinedMesh piece;
  if (absl::Status s = AppendInputParents(p, part, refined.tet_parent, piece.tet_parent); !s.ok()) {
    return s;
  }
  piece.mesh = std::move(refined.mesh);
  piece.tet_iteration = std::move(refined.tet_iteration);
  piece.tet_quality = std::move(refined.tet_quality);
  return piece;
}

absl::StatusOr<RefinedMesh> MergeParts(const Mesh& input, const Volume& volume,
                                       OutsidePolicy outside, const std::vector<MeshPart>& parts,
                                       const std::vector<const RefineResult*>& results) {
  if (parts.size() != results.size()) {
    return absl::InternalError("MergeParts: one result per part expected");
  }
  RefinedMesh out;
  Mesh& merged = out.mesh;
  const size_t num_input = input.points.size();
  merged.points = input.points;
  merged.values.assign(num_input, 0.0);
  std::vector<uint8_t> assigned(num_input, 0);
  size_t total_tets = 0;
  for (const RefineResult* r : results) total_tets += r->mesh.tets.size();
  merged.tets.reserve(total_tets);
  out.tet_iteration.reserve(total_tets);
  out.tet_quality.reserve(total_tets);

  absl::flat_hash_map<PointKey, uint32_t> shared;
  std::vector<uint32_t> to_merged;
  for (size_t p = 0; p < parts.size(); ++p) {
    const MeshPart& part = parts[p];
    const Mesh& refined = results[p]->mesh;
    const size_t num_own = part.mesh.points.size();
    if (refined.points.size() < num_own || refined.values.size() != refined.points.size()) {
      return absl::InternalError(absl::StrCat("part ", p, ": the refined mesh has fewer vertices (",
                                              refined.points.size(), ") than the part sent (",
                                              num_own, ") or no value per vertex"));
    }
    to_merged.assign(refined.points.size(), kUnsetIndex);
    for (size_t j = 0; j < num_own; ++j) {
      if (KeyOf(refined.points[j]) != KeyOf(part.mesh.points[j])) {
        return absl::InternalError(absl::StrCat("part ", p, ": refined vertex ", j,
                                                " is not input vertex ", j,
                                                "; merging relies on input vertices coming first"));
      }
      const uint32_t v = part.input_vertex[j];
      if (assigned[v] != 0 && !SameBits(merged.values[v], refined.values[j])) {
        return absl::InternalError(absl::StrCat("parts disagree on the value at input vertex ", v));
      }
      merged.values[v] = refined.values[j];
      assigned[v] = 1;
      to_merged[j] = v;
    }
    for (size_t j = num_own; j < refined.points.size(); ++j) {
      const Vec3& point = refined.points[j];
      const uint32_t next = static_cast<uint32_t>(merged.points.size());
      if (InAnotherBox(point, parts, p)) {
        const auto [it, inserted] = shared.try_emplace(KeyOf(point), next);
        if (!inserted) {
          if (!SameBits(merged.values[it->second], refined.values[j])) {
            return absl::InternalError(absl::StrCat("parts disagree on the value at vertex (",
                                                    point[0], ", ", point[1], ", ", point[2], ")"));
          }
          to_merged[j] = it->second;
          continue;
        }
      }
      merged.points.push_back(point);
      merged.values.push_back(refined.values[j]);
      to_merged[j] = next;
    }
    for (const Tet& t : refined.tets) {
      merged.tets.push_back({to_merged[t[0]], to_merged[t[1]], to_merged[t[2]], to_merged[t[3]]});
    }
    out.tet_iteration.insert(out.tet_iteration.end(), results[p]->tet_iteration.begin(),
                             results[p]->tet_iteration.end());
    out.tet_quality.insert(out.tet_quality.end(), results[p]->tet_quality.begin(),
                           results[p]->tet_quality.end());
    merged.labels.insert(merged.labels.end(), refined.labels.begin(), refined.labels.end());
    if (absl::Status s =
            AppendInputParents(static_cast<int>(p), part, results[p]->tet_parent, out.tet_parent);
        !s.ok()) {
      return s;
    }
  }
  for (size_t v = 0; v < num_input; ++v) {
    if (assigned[v] != 0) continue;
    Vec3 u = volume.ContinuousIndex(input.points[v]);
    if (outside == OutsidePolicy::kClamp) u = volume.ClampToGrid(u);
    merged.values[v] = volume.SampleIndex(u);
  }
  return out;
}

}  // namespace tetrefine::sharding
