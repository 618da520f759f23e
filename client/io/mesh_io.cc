#include "client/io/mesh_io.h"

#include <algorithm>
#include <filesystem>
#include <string>
#include <vector>

#include "absl/strings/match.h"
#include "absl/strings/str_cat.h"
#include "client/io/abaqus_format.h"
#include "client/io/file_bytes.h"
#include "client/io/gmsh_format.h"
#include "client/io/io_error.h"
#include "client/io/medit_format.h"
#include "client/io/mesh_frame.h"
#include "client/io/pvtu_reader.h"
#include "client/io/tetgen_format.h"
#include "client/io/vtk_legacy_format.h"
#include "client/io/vtu_format.h"

namespace tetrefine::io {
namespace {

enum class MeshFormat {
  kVtu,
  kPvtu,
  kVtkLegacy,
  kGmsh,
  kMedit,
  kMeshb,
  kTetgen,
  kAbaqus,
  kUnknown
};

MeshFormat FormatOf(const std::string& path) {
  if (absl::EndsWithIgnoreCase(path, ".vtu")) return MeshFormat::kVtu;
  if (absl::EndsWithIgnoreCase(path, ".pvtu")) return MeshFormat::kPvtu;
  if (absl::EndsWithIgnoreCase(path, ".vtk")) return MeshFormat::kVtkLegacy;
  if (absl::EndsWithIgnoreCase(path, ".msh")) return MeshFormat::kGmsh;
  if (absl::EndsWithIgnoreCase(path, ".mesh")) return MeshFormat::kMedit;
  if (absl::EndsWithIgnoreCase(path, ".meshb")) return MeshFormat::kMeshb;
  if (absl::EndsWithIgnoreCase(path, ".ele")) return MeshFormat::kTetgen;
  if (absl::EndsWithIgnoreCase(path, ".inp")) return MeshFormat::kAbaqus;
  return MeshFormat::kUnknown;
}

}  // namespace

bool IsMeshPath(const std::string& path) { return FormatOf(path) != MeshFormat::kUnknown; }

namespace {
constexpr const char* kSurfaceExtensions[] = {".stl", ".ply",  ".obj",  ".off",
                                              ".vtp", ".poly", ".smesh"};
}  // namespace

bool IsSurfacePath(const std::string& path) {
  for (const char* surface : kSurfaceExtensions) {
    if (absl::EndsWithIgnoreCase(path, surface)) return true;
  }
  return false;
}

absl::Status UnknownExtension(const std::string& path) {
  // Surface files are what people most often have before a volume mesh exists: say what to do.
  if (IsSurfacePath(path)) {
    const std::string extension = path.substr(path.find_last_of('.'));
    const std::string name = path.substr(path.find_last_of('/') + 1);
    // TetGen reads .stl, .ply, .off, .poly and .smesh itself; .obj and .vtp need a conversion.
    const bool tetgen_reads =
        !absl::EqualsIgnoreCase(extension, ".obj") && !absl::EqualsIgnoreCase(extension, ".vtp");
    return FileError(
        path,
        absl::StrCat("a ", extension,
                     " file is a surface, not a tetrahedral mesh: fill it with tets first, ",
                     tetgen_reads ? absl::StrCat("e.g. `tetgen -pq ", name,
                                                 "` (writes a .1.ele that tetrefine reads) or Gmsh")
                                  : "e.g. save it as .stl (meshio, ParaView) and run `tetgen -pq` "
                                    "on that (it writes a .1.ele that tetrefine reads), or Gmsh"));
  }
  return FileError(path,
                   "unknown extension for a mesh: expected .vtu, .pvtu, .vtk, .msh, .mesh, "
                   ".meshb, .ele (TetGen, with its .node) or .inp (Abaqus)");
}

bool IsWritableMeshPath(const std::string& path) {
  const MeshFormat format = FormatOf(path);
  return format != MeshFormat::kUnknown && format != MeshFormat::kPvtu &&
         format != MeshFormat::kAbaqus;
}

absl::StatusOr<MeshFile> ReadMesh(const std::string& path) {
  const MeshFormat format = FormatOf(path);
  if (format == MeshFormat::kUnknown) return UnknownExtension(path);
  if (format == MeshFormat::kPvtu) {
    absl::StatusOr<MeshFile> merged = ReadPvtu(path);
    if (!merged.ok()) return merged.status();
    if (absl::Status s = ValidateMeshFile(*merged, path); !s.ok()) return s;
    return merged;
  }
  absl::StatusOr<FileView> view = FileView::Open(path);
  if (!view.ok()) return view.status();
  const absl::string_view text = view->bytes();
  absl::StatusOr<MeshFile> file;
  absl::StatusOr<FileView> nodes = absl::UnknownError("");
  if (format == MeshFormat::kTetgen) {
    const std::string node_path = TetgenNodePath(path);
    nodes = FileView::Open(node_path);
    if (!nodes.ok()) {
      return absl::Status(nodes.status().code(),
                          absl::StrCat(path, ": TetGen keeps the points in ", node_path, ": ",
                                       nodes.status().message()));
    }
    file = ParseTetgen(nodes->bytes(), text, node_path, path);
  }
  switch (format) {
    case MeshFormat::kVtu:
      file = ParseVtu(text, path);
      break;
    case MeshFormat::kVtkLegacy:
      file = ParseVtkLegacy(text, path);
      break;
    case MeshFormat::kGmsh:
      file = ParseGmsh(text, path);
      break;
    case MeshFormat::kMedit:
      file = ParseMedit(text, path);
      break;
    case MeshFormat::kMeshb:
      file = ParseMeshb(text, path);
      break;
    case MeshFormat::kAbaqus:
      file = ParseAbaqus(text, path, [&path](absl::string_view name) {
        return ReadFileBytes(
            (std::filesystem::path(path).parent_path() / std::string(name)).string());
      });
      break;
    case MeshFormat::kTetgen:  // read above, with its .node
    case MeshFormat::kPvtu:
    case MeshFormat::kUnknown:
      break;
  }
  if (!file.ok()) return file.status();
  // Every parser checks its own structure; this catches what they share (finite numbers,
  // indices in range, array lengths) in one place.
  DropNonFiniteDerivedArrays(&*file);
  if (absl::Status s = ValidateMeshFile(*file, path); !s.ok()) return s;
  return file;
}

namespace {

// .vtu (field data SPACE) and .vtk (the title's SPACE=) say which frame their points are in.
bool CarriesFrameTag(MeshFormat format) {
  return format == MeshFormat::kVtu || format == MeshFormat::kVtkLegacy;
}

}  // namespace

bool LpsTagLost(const std::string& path, const MeshFile& file) {
  const MeshFormat format = FormatOf(path);
  return file.frame == MeshFrame::kLps && format != MeshFormat::kUnknown &&
         format != MeshFormat::kPvtu && !CarriesFrameTag(format);
}

std::vector<int32_t> NegativeGmshLabels(const std::string& path, const MeshFile& file) {
  std::vector<int32_t> negative;
  if (FormatOf(path) != MeshFormat::kGmsh) return negative;
  for (int32_t label : file.mesh.labels) {
    if (label < 0) negative.push_back(label);
  }
  std::sort(negative.begin(), negative.end());
  negative.erase(std::unique(negative.begin(), negative.end()), negative.end());
  return negative;
}

namespace {

// The files WriteMesh writes for `path`, each with its bytes: one, or a TetGen .node and .ele.
struct EncodedFile {
  std::string path;
  std::string bytes;
};

absl::StatusOr<std::vector<EncodedFile>> Encode(const std::string& path, const MeshFile& file,
                                                const MeshWriteOptions& options) {
  const MeshFormat format = FormatOf(path);
  if (format == MeshFormat::kUnknown) {
    return FileError(path,
                     "unknown extension for a mesh to write: expected .vtu, .vtk, .msh, .mesh, "
                     ".meshb or .ele (TetGen, with its .node)");
  }
  if (format == MeshFormat::kAbaqus) {
    return FileError(path,
                     "Abaqus .inp is read, not written: write .vtu, .msh (which keeps the region "
                     "names) or another mesh format");
  }
  if (format == MeshFormat::kPvtu) {
    return FileError(path,
                     "a .pvtu is written as pieces, one per shard (refine --shards K --pvtu, or "
                     "io::WritePvtu), not as one mesh");
  }
  if (absl::Status s = ValidateMeshFile(file, path); !s.ok()) return s;
  if (file.frame == MeshFrame::kLps && !CarriesFrameTag(format)) {
    // No place for the tag: the input's own numbers are written, so that every input vertex
    // keeps its coordinates in every output format (an LPS file came back in RAS as .msh,
    // .mesh and .meshb, x and y negated without a word; found by a file-format sweep). Callers
    // warn that the tag is lost (LpsTagLost).
    MeshFile stored = file;
    for (Vec3& p : stored.mesh.points) {
      for (int a = 0; a < 3; ++a) p[a] *= FrameSign(MeshFrame::kLps, a);
    }
    stored.frame = MeshFrame::kUntagged;
    return Encode(path, stored, options);
  }
  std::string bytes;
  switch (format) {
    case MeshFormat::kVtu:
      bytes = FormatVtu(file, options.vtu);
      break;
    case MeshFormat::kVtkLegacy:
      bytes = FormatVtkLegacy(file, {.binary = options.binary});
      break;
    case MeshFormat::kGmsh:
      bytes = FormatGmsh41(file, {.binary = options.binary});
      break;
    case MeshFormat::kMedit:
      bytes = FormatMedit(file);
      break;
    case MeshFormat::kMeshb:
      bytes = FormatMeshb(file, {.version = options.meshb_version});
      break;
    case MeshFormat::kTetgen: {
      TetgenFiles files = FormatTetgen(file);
      std::vector<EncodedFile> out;
      out.push_back({TetgenNodePath(path), std::move(files.node)});
      out.push_back({path, std::move(files.ele)});
      return out;
    }
    case MeshFormat::kAbaqus:
    case MeshFormat::kPvtu:
    case MeshFormat::kUnknown:
      break;
  }
  std::vector<EncodedFile> out;
  out.push_back({path, std::move(bytes)});
  return out;
}

}  // namespace

absl::StatusOr<std::string> FormatMesh(const std::string& path, const MeshFile& file,
                                       const MeshWriteOptions& options) {
  absl::StatusOr<std::vector<EncodedFile>> files = Encode(path, file, options);
  if (!files.ok()) return files.status();
  if (files->size() == 1) return std::move((*files)[0].bytes);
  std::string all;
  for (const EncodedFile& f : *files) all += f.bytes;
  return all;
}

absl::Status StageMesh(const std::string& path, const MeshFile& file,
                       const MeshWriteOptions& options, StagedFiles& staged) {
  absl::StatusOr<std::vector<EncodedFile>> files = Encode(path, file, options);
  if (!files.ok()) return files.status();
  for (const EncodedFile& f : *files) {
    if (absl::Status s = staged.Write(f.path, f.bytes); !s.ok()) return s;
  }
  return absl::OkStatus();
}

absl::Status WriteMesh(const std::string& path, const MeshFile& file,
                       const MeshWriteOptions& options) {
  absl::StatusOr<std::vector<EncodedFile>> files = Encode(path, file, options);
  if (!files.ok()) return files.status();
  if (files->size() == 1) return WriteFileAtomically((*files)[0].path, (*files)[0].bytes);
  // A TetGen pair is staged whole and renamed into place together (the .node first), so that a
  // failure or a signal during either write leaves the pair of a run before as it was. Written
  // and renamed one by one, `mesh --output X.ele` killed during the .ele left the new X.node
  // beside the old X.ele, which `info` read as a mesh with 20,037 inverted tets (an outside
  // review, 2026-11-29); refine, which finishes a write it has started, did not.
  StagedFiles staged;
  for (const EncodedFile& f : *files) {
    if (absl::Status s = staged.Write(f.path, f.bytes); !s.ok()) return s;
  }
  return staged.Commit();
}

}  // namespace tetrefine::io
