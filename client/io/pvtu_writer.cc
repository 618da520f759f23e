#include "client/io/pvtu_writer.h"

#include <filesystem>

#include "absl/strings/str_cat.h"
#include "client/io/file_bytes.h"
#include "client/io/xml_escape.h"

namespace tetrefine::io {
namespace {

// Which optional arrays a mesh file holds; pieces of one dataset must agree on it, since the
// index declares one set for all of them.
std::string ArraySignature(const MeshFile& file) {
  return absl::StrCat(file.mesh.values.empty() ? "" : "value ",
                      file.tet_iteration.empty() ? "" : "iteration ",
                      file.tet_quality.empty() ? "" : "quality ",
                      file.mesh.labels.empty() ? "" : LabelArrayName(file));
}

}  // namespace

std::string FormatPvtu(const MeshFile& like, const std::vector<std::string>& sources) {
  std::string out =
      "<?xml version=\"1.0\"?>\n"
      "<VTKFile type=\"PUnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" "
      "header_type=\"UInt64\">\n"
      "  <PUnstructuredGrid GhostLevel=\"0\">\n";
  if (!like.mesh.values.empty()) {
    out +=
        "    <PPointData Scalars=\"value\">\n"
        "      <PDataArray type=\"Float64\" Name=\"value\"/>\n"
        "    </PPointData>\n";
  }
  if (!like.tet_iteration.empty() || !like.tet_quality.empty() || !like.mesh.labels.empty()) {
    out += "    <PCellData>\n";
    if (!like.tet_iteration.empty()) {
      out += "      <PDataArray type=\"Int32\" Name=\"iteration\"/>\n";
    }
    if (!like.tet_quality.empty()) {
      out += "      <PDataArray type=\"Float32\" Name=\"quality\"/>\n";
    }
    if (!like.mesh.labels.empty()) {
      absl::StrAppend(&out, "      <PDataArray type=\"Int32\" Name=\"",
                      EscapeXml(LabelArrayName(like)), "\"/>\n");
    }
    out += "    </PCellData>\n";
  }
  out +=
      "    <PPoints>\n"
      "      <PDataArray type=\"Float64\" Name=\"Points\" NumberOfComponents=\"3\"/>\n"
      "    </PPoints>\n";
  for (const std::string& source : sources) {
    absl::StrAppend(&out, "    <Piece Source=\"", EscapeXml(source), "\"/>\n");
  }
  out += "  </PUnstructuredGrid>\n</VTKFile>\n";
  return out;
}

std::string PvtuPiecePath(const std::string& path, int k) {
  std::filesystem::path piece(path);
  piece.replace_filename(absl::StrCat(piece.stem().string(), "_", k, ".vtu"));
  return piece.string();
}

absl::Status WritePvtu(const std::string& path, const std::vector<MeshFile>& pieces,
                       const VtuWriteOptions& options) {
  if (pieces.empty()) return absl::InvalidArgumentError(absl::StrCat(path, ": no pieces"));
  const std::string signature = ArraySignature(pieces[0]);
  // Every piece and the index first, then all renamed into place: a failure leaves the files of
  // a run before as they were, never its index over a mix of pieces.
  StagedFiles staged;
  std::vector<std::string> sources;
  for (size_t k = 0; k < pieces.size(); ++k) {
    const std::string piece_path = PvtuPiecePath(path, static_cast<int>(k));
    if (absl::Status s = ValidateMeshFile(pieces[k], piece_path); !s.ok()) return s;
    if (ArraySignature(pieces[k]) != signature) {
      return absl::InvalidArgumentError(
          absl::StrCat(path, ": piece ", k, " holds the arrays [", ArraySignature(pieces[k]),
                       "], piece 0 [", signature, "]; an index declares one set for all"));
    }
    if (absl::Status s = staged.Write(piece_path, FormatVtu(pieces[k], options)); !s.ok()) {
      return s;
    }
    sources.push_back(std::filesystem::path(piece_path).filename().string());
  }
  if (absl::Status s = staged.Write(path, FormatPvtu(pieces[0], sources)); !s.ok()) return s;
  return staged.Commit();
}

}  // namespace tetrefine::io
