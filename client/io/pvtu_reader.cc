// Reading a parallel unstructured grid (.pvtu) as one mesh. See pvtu_reader.h.
#include "client/io/pvtu_reader.h"

#include <array>
#include <cstring>
#include <unordered_map>
#include <utility>

#include "absl/hash/hash.h"
#include "absl/strings/str_cat.h"
#include "client/io/file_bytes.h"
#include "client/io/io_error.h"
#include "client/io/vtk_xml_file.h"
#include "client/io/vtu_format.h"

namespace tetrefine::io {
namespace {

// The bits of a point's coordinates, +0.0 for -0.0 (the same place).
using PointKey = std::array<uint64_t, 3>;

PointKey KeyOf(const Vec3& p) {
  PointKey key;
  for (int a = 0; a < 3; ++a) {
    const double x = p[a] == 0.0 ? 0.0 : p[a];
    std::memcpy(&key[a], &x, sizeof(double));
  }
  return key;
}

struct PointKeyHash {
  size_t operator()(const PointKey& k) const { return absl::HashOf(k[0], k[1], k[2]); }
};

// What every piece must share, for messages: "values", "labels \"region\"", ...
std::string ArraysOf(const MeshFile& f) {
  std::string out;
  const auto add = [&out](absl::string_view what) {
    absl::StrAppend(&out, out.empty() ? "" : ", ", what);
  };
  if (!f.mesh.values.empty()) add("value");
  if (!f.tet_iteration.empty()) add("iteration");
  if (!f.tet_quality.empty()) add("quality");
  if (!f.mesh.labels.empty()) add(absl::StrCat("labels \"", LabelArrayName(f), "\""));
  if (f.frame != MeshFrame::kUntagged) add(absl::StrCat("SPACE ", FrameTag(f.frame)));
  return out.empty() ? std::string("no arrays") : out;
}

}  // namespace

absl::StatusOr<std::vector<std::string>> ParsePvtuIndex(absl::string_view text,
                                                        absl::string_view path) {
  VtkXmlFile xml;
  if (absl::Status s = OpenVtkXml(text, path, "PUnstructuredGrid", xml); !s.ok()) return s;
  return PieceSources(xml, path);
}

absl::StatusOr<MeshFile> MergePvtuPieces(std::vector<MeshFile> pieces,
                                         const std::vector<std::string>& paths) {
  if (pieces.empty()) return absl::InvalidArgumentError("a .pvtu needs at least one piece");
  MeshFile out;
  out.label_name = pieces[0].label_name;
  out.frame = pieces[0].frame;
  const std::string first_arrays = ArraysOf(pieces[0]);          // pieces[0] is emptied below
  std::unordered_map<PointKey, uint32_t, PointKeyHash> earlier;  // points of earlier pieces
  for (size_t k = 0; k < pieces.size(); ++k) {
    MeshFile& piece = pieces[k];
    if (ArraysOf(piece) != first_arrays) {
      return absl::InvalidArgumentError(absl::StrCat(paths[k], ": piece ", k, " holds ",
                                                     ArraysOf(piece), ", but piece 0 (", paths[0],
                                                     ") holds ", first_arrays));
    }
    std::vector<uint32_t> index(piece.mesh.points.size());
    std::vector<std::pair<PointKey, uint32_t>> added;
    for (size_t i = 0; i < piece.mesh.points.size(); ++i) {
      const PointKey key = KeyOf(piece.mesh.points[i]);
      const auto found = earlier.find(key);
      if (found != earlier.end()) {
        index[i] = found->second;
        if (!out.mesh.values.empty() && out.mesh.values[found->second] != piece.mesh.values[i]) {
          return absl::InvalidArgumentError(
              absl::StrCat(paths[k], ": vertex ", i, " of piece ", k,
                           " is at a vertex of an earlier piece but has value ",
                           piece.mesh.values[i], " there, not ", out.mesh.values[found->second]));
        }
        continue;
      }
      if (out.mesh.points.size() >= (size_t{1} << 32) - 1) {
        return absl::InvalidArgumentError(
            absl::StrCat(paths[k], ": the pieces hold more than 2^32 - 1 vertices together"));
      }
      index[i] = static_cast<uint32_t>(out.mesh.points.size());
      out.mesh.points.push_back(piece.mesh.points[i]);
      if (!piece.mesh.values.empty()) out.mesh.values.push_back(piece.mesh.values[i]);
      added.emplace_back(key, index[i]);
    }
    for (const auto& [key, i] : added) earlier.emplace(key, i);  // the first of repeats wins
    for (const Tet& t : piece.mesh.tets) {
      out.mesh.tets.push_back({index[t[0]], index[t[1]], index[t[2]], index[t[3]]});
    }
    out.mesh.labels.insert(out.mesh.labels.end(), piece.mesh.labels.begin(),
                           piece.mesh.labels.end());
    out.tet_iteration.insert(out.tet_iteration.end(), piece.tet_iteration.begin(),
                             piece.tet_iteration.end());
    out.tet_quality.insert(out.tet_quality.end(), piece.tet_quality.begin(),
                           piece.tet_quality.end());
    out.ghost_cells_skipped += piece.ghost_cells_skipped;
    for (const auto& [kind, count] : piece.skipped_cells) out.skipped_cells[kind] += count;
    for (std::string& dropped : piece.dropped_arrays) {
      if (std::find(out.dropped_arrays.begin(), out.dropped_arrays.end(), dropped) ==
          out.dropped_arrays.end()) {
        out.dropped_arrays.push_back(std::move(dropped));
      }
    }
    piece = MeshFile{};  // its memory back before the next one grows `out`
  }
  return out;
}

absl::StatusOr<MeshFile> ReadPvtu(const std::string& path) {
  absl::StatusOr<FileView> index = FileView::Open(path);
  if (!index.ok()) return index.status();
  absl::StatusOr<std::vector<std::string>> sources = ParsePvtuIndex(index->bytes(), path);
  if (!sources.ok()) return sources.status();
  std::vector<MeshFile> pieces;
  for (const std::string& source : *sources) {
    absl::StatusOr<FileView> view = FileView::Open(source);
    if (!view.ok()) {
      return absl::Status(view.status().code(), absl::StrCat(path, ": piece ", pieces.size(), ": ",
                                                             view.status().message()));
    }
    absl::StatusOr<MeshFile> piece = ParseVtu(view->bytes(), source);
    if (!piece.ok()) return piece.status();
    pieces.push_back(*std::move(piece));
  }
  return MergePvtuPieces(std::move(pieces), *sources);
}

}  // namespace tetrefine::io
