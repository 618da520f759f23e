#include "tools/reproduce/plaza_peer.h"

#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "client/io/json_writer.h"
#include "client/io/mesh_io.h"
#include "google/protobuf/struct.pb.h"
#include "google/protobuf/util/json_util.h"
#include "tools/reproduce/npy_writer.h"
#include "tools/reproduce/subprocess.h"

namespace tetrefine::reproduce {
namespace {

// plaza_refine.py's exit status when python3-dolfinx does not import.
constexpr int kDolfinxMissing = 3;

absl::Status WriteBytes(const std::filesystem::path& path, const std::string& bytes) {
  std::ofstream f(path, std::ios::binary | std::ios::trunc);
  f << bytes;
  f.close();
  if (!f) return absl::InternalError(absl::StrCat("cannot write ", path.string()));
  return absl::OkStatus();
}

absl::StatusOr<std::string> ReadText(const std::filesystem::path& path) {
  std::ifstream f(path, std::ios::binary);
  if (!f) return absl::NotFoundError(absl::StrCat("cannot read ", path.string()));
  std::ostringstream s;
  s << f.rdbuf();
  return s.str();
}

// Reads a field of the script's JSON object; a missing or mistyped field is an error naming it.
class ReportFields {
 public:
  ReportFields(const google::protobuf::Struct& root, std::string path)
      : root_(root), path_(std::move(path)) {}

  double Number(std::initializer_list<const char*> keys) {
    const google::protobuf::Value* v = Find(keys);
    if (v == nullptr) return 0.0;
    if (!v->has_number_value()) Fail(keys, "is not a number");
    return v->number_value();
  }
  std::string Text(std::initializer_list<const char*> keys) {
    const google::protobuf::Value* v = Find(keys);
    if (v == nullptr) return "";
    if (!v->has_string_value()) Fail(keys, "is not a string");
    return v->string_value();
  }
  const absl::Status& status() const { return status_; }

 private:
  const google::protobuf::Value* Find(std::initializer_list<const char*> keys) {
    const google::protobuf::Struct* object = &root_;
    const google::protobuf::Value* v = nullptr;
    for (const char* key : keys) {
      if (object == nullptr) break;
      const auto it = object->fields().find(key);
      if (it == object->fields().end()) {
        Fail(keys, "is missing");
        return nullptr;
      }
      v = &it->second;
      object = v->has_struct_value() ? &v->struct_value() : nullptr;
    }
    return v;
  }
  void Fail(std::initializer_list<const char*> keys, const char* what) {
    if (!status_.ok()) return;
    std::string name;
    for (const char* k : keys) absl::StrAppend(&name, name.empty() ? "" : ".", k);
    status_ = absl::DataLossError(absl::StrCat(path_, ": field ", name, " ", what));
  }

  const google::protobuf::Struct& root_;
  std::string path_;
  absl::Status status_;
};

}  // namespace

absl::Status CheckPlaza(const PlazaPeer& peer) {
  if (!std::filesystem::exists(peer.script)) {
    return absl::NotFoundError(absl::StrCat("plaza script ", peer.script, " not found"));
  }
  if (!std::filesystem::exists(peer.python)) {
    return absl::NotFoundError(absl::StrCat(peer.python, " not found"));
  }
  const absl::StatusOr<int> status = RunProcess({peer.python, peer.script, "--check"});
  if (!status.ok()) return status.status();
  if (*status == kDolfinxMissing) return absl::NotFoundError("python3-dolfinx missing");
  if (*status != 0) {
    return absl::InternalError(absl::StrCat(peer.script, " --check exited with ", *status));
  }
  return absl::OkStatus();
}

absl::Status ExportPlazaCase(const Volume& volume, const Mesh& mesh, double norm_coeff,
                             const std::filesystem::path& dir) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec)
    return absl::InternalError(absl::StrCat("cannot create ", dir.string(), ": ", ec.message()));
  if (absl::Status s = WriteBytes(dir / "volume.npy", VolumeNpy(volume)); !s.ok()) return s;
  io::JsonWriter w;
  w.BeginObject();
  const GridGeometry& g = volume.grid();
  w.Key("origin");
  w.BeginArray();
  for (double x : g.origin) w.Number(x);
  w.EndArray();
  w.Key("spacing");
  w.BeginArray();
  for (double x : g.spacing) w.Number(x);
  w.EndArray();
  if (!volume.axis_aligned()) {
    // An oblique grid: the script maps world to index with this matrix, operation by operation
    // as Volume::ContinuousIndex does, so its samples are core's bits.
    w.Key("world_to_index");
    w.BeginArray();
    for (double x : volume.world_to_index()) w.Number(x);
    w.EndArray();
  }
  w.Field("norm_coeff", norm_coeff);
  w.EndObject();
  if (absl::Status s = WriteBytes(dir / "case.json", w.Take()); !s.ok()) return s;
  io::MeshFile file;
  file.mesh.points = mesh.points;
  file.mesh.tets = mesh.tets;
  // Inline base64 without compression: the layout plaza_refine.py parses with ElementTree (the
  // default, ParaView's appended raw section, is not well-formed XML to a plain XML parser).
  io::MeshWriteOptions layout;
  layout.vtu.layout = io::VtuWriteOptions::Layout::kInlineBase64;
  layout.vtu.compressor = io::VtkCompressor::kNone;
  return io::WriteMesh((dir / "mesh.vtu").string(), file, layout);
}

absl::StatusOr<PlazaResult> RunPlaza(const PlazaPeer& peer, const std::filesystem::path& case_dir,
                                     double epsilon) {
  const std::string stem = absl::StrFormat("plaza_eps%g", epsilon);
  const std::filesystem::path json_path = case_dir / (stem + ".json");
  const std::filesystem::path mesh_path = case_dir / (stem + ".vtu");
  std::filesystem::remove(json_path);
  std::filesystem::remove(mesh_path);
  const absl::StatusOr<int> status =
      RunProcess({peer.python, peer.script, "--case", case_dir.string(), "--epsilon",
                  absl::StrFormat("%.17g", epsilon), "--max-rounds", absl::StrCat(peer.max_rounds),
                  "--max-tets", absl::StrCat(peer.max_tets), "--output", json_path.string(),
                  "--mesh-out", mesh_path.string(), "--quiet"});
  if (!status.ok()) return status.status();
  if (*status != 0) {
    return absl::InternalError(
        absl::StrCat(peer.script, " exited with status ", *status, " on ", case_dir.string()));
  }
  absl::StatusOr<std::string> text = ReadText(json_path);
  if (!text.ok()) return text.status();
  google::protobuf::Struct root;
  if (const auto s = google::protobuf::util::JsonStringToMessage(*text, &root); !s.ok()) {
    return absl::DataLossError(
        absl::StrCat(json_path.string(), ": not JSON: ", std::string(s.message())));
  }
  ReportFields f(root, json_path.string());
  PlazaResult out;
  PeerSelfReport& r = out.report;
  r.version = absl::StrCat("DOLFINx ", f.Text({"dolfinx_version"}));
  r.rounds = static_cast<int>(f.Number({"rounds"}));
  r.stop_reason = f.Text({"stop_reason"});
  r.seconds = f.Number({"seconds"});
  r.setup_seconds = f.Number({"setup_seconds"});
  r.tets = static_cast<int64_t>(f.Number({"tets"}));
  r.midpoint_max = f.Number({"midpoint_max"});
  r.lattice_max = f.Number({"lattice", "max_error"});
  r.lattice_mean = f.Number({"lattice", "mean_error"});
  r.quality_min = f.Number({"quality", "min"});
  r.quality_mean = f.Number({"quality", "mean"});
  if (!f.status().ok()) return f.status();
  absl::StatusOr<io::MeshFile> mesh = io::ReadMesh(mesh_path.string());
  if (!mesh.ok()) return mesh.status();
  out.mesh.points = std::move(mesh->mesh.points);
  out.mesh.tets = std::move(mesh->mesh.tets);
  return out;
}

}  // namespace tetrefine::reproduce
