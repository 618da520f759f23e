// File-format speed and size: reads a mesh, then writes and re-reads it in every format and
// variant, printing the best of a few runs (wall time, so parallel compression counts as it is
// felt) and bytes per tet. Region labels, iteration and quality are added when the input lacks
// them, so the arrays are those of a refined mesh.
//
//   mesh_io_bench MESH [REPEATS [FORMAT-PREFIX]]   e.g. mesh_io_bench refined.vtu 3 "vtu appended
//   z"
//
// bench/file_to_file.sh runs it on a refined 1.6 M-tet mesh beside `gmsh -refine`.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <string>
#include <string_view>

#include "client/io/file_bytes.h"
#include "client/io/mesh_io.h"
#include "client/io/vtk_compressor.h"
#include "core/quality.h"

namespace tetrefine::io {
namespace {

double Seconds(const std::function<void()>& work, int repeats) {
  double best = 1e30;
  for (int r = 0; r < repeats; ++r) {
    const auto start = std::chrono::steady_clock::now();
    work();
    best = std::min(
        best, std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  }
  return best;
}

int Run(const std::string& input, int repeats, std::string_view only) {
  absl::StatusOr<MeshFile> file;
  const double read = Seconds([&] { file = ReadMesh(input); }, repeats);
  if (!file.ok()) {
    std::fprintf(stderr, "%s\n", file.status().ToString().c_str());
    return 1;
  }
  const size_t t = file->mesh.tets.size();
  std::printf("input %s: %zu vertices, %zu tets, read in %.3f s (%.1f M tets/s)\n", input.c_str(),
              file->mesh.points.size(), t, read, t / read / 1e6);
  if (file->mesh.labels.empty()) {
    file->mesh.labels.assign(t, 1);
    file->label_name = "region";
  }
  if (file->tet_iteration.empty()) file->tet_iteration.assign(t, 0);
  if (file->tet_quality.empty()) {
    for (const Tet& tet : file->mesh.tets) {
      const auto& p = file->mesh.points;
      file->tet_quality.push_back(
          static_cast<float>(MeanRatio(p[tet[0]], p[tet[1]], p[tet[2]], p[tet[3]])));
    }
  }
  if (file->mesh.values.empty()) file->mesh.values.assign(file->mesh.points.size(), 1.0);

  struct Variant {
    const char* name;
    const char* extension;
    MeshWriteOptions options;
  };
  using Layout = VtuWriteOptions::Layout;
  const Variant variants[] = {
      {"vtu appended zlib (default)", ".vtu", {}},
      // The faster zlib coder whose bytes vary from run to run (client/io/vtu_writer.cc).
      {"vtu appended zlib ISA-L", ".vtu", {.vtu = {.level = tetrefine::io::kFastestZlibLevel}}},
      {"vtu appended lz4", ".vtu", {.vtu = {.compressor = VtkCompressor::kLz4}}},
      {"vtu appended lzma", ".vtu", {.vtu = {.compressor = VtkCompressor::kLzma}}},
      {"vtu appended raw", ".vtu", {.vtu = {.compressor = VtkCompressor::kNone}}},
      {"vtu inline base64 zlib", ".vtu", {.vtu = {.layout = Layout::kInlineBase64}}},
      {"msh 4.1 binary", ".msh", {.binary = true}},
      {"msh 4.1 ascii", ".msh", {}},
      {"vtk binary", ".vtk", {.binary = true}},
      {"meshb", ".meshb", {}},
      {"tetgen .node + .ele", ".ele", {}},
  };
  const std::string dir = std::filesystem::temp_directory_path() / "tetrefine_mesh_io_bench";
  std::filesystem::create_directories(dir);
  std::printf("%-30s %10s %10s %10s %12s %14s\n", "format", "encode s", "write s", "read s",
              "bytes/tet", "M tets/s enc.");
  for (const Variant& v : variants) {
    if (!std::string_view(v.name).starts_with(only)) continue;
    const std::string path = dir + "/out" + v.extension;
    // Encoding (what this library does) apart from writing the bytes (what the disk does).
    absl::StatusOr<std::string> bytes;
    const double encode = Seconds([&] { bytes = FormatMesh(path, *file, v.options); }, repeats);
    absl::Status status;
    const double write = Seconds([&] { status = WriteMesh(path, *file, v.options); }, repeats);
    if (!bytes.ok() || !status.ok()) {
      std::fprintf(stderr, "%s %s\n", bytes.status().ToString().c_str(), status.ToString().c_str());
      return 1;
    }
    absl::StatusOr<MeshFile> back;
    const double reread = Seconds([&] { back = ReadMesh(path); }, repeats);
    if (!back.ok() || back->mesh.tets != file->mesh.tets) {
      std::fprintf(stderr, "%s: read back differs\n", path.c_str());
      return 1;
    }
    std::printf("%-30s %10.3f %10.3f %10.3f %12.2f %14.1f\n", v.name, encode, write, reread,
                static_cast<double>(bytes->size()) / t, t / encode / 1e6);
  }
  std::filesystem::remove_all(dir);
  return 0;
}

}  // namespace
}  // namespace tetrefine::io

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: %s MESH [REPEATS [FORMAT-PREFIX]]\n", argv[0]);
    return 2;
  }
  return tetrefine::io::Run(argv[1], argc > 2 ? std::atoi(argv[2]) : 3, argc > 3 ? argv[3] : "");
}
