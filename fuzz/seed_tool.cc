// Writes the generated part of the seed corpora: fuzz/corpus/<target>/seed-<name> for the
// request, refine, mesh and NIfTI targets, from small valid data. Hand-written seeds (other
// format variants) sit beside them. Run from anywhere: fuzz_seed_tool <repo>/fuzz/corpus

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <vector>

#include "client/io/gmsh_format.h"
#include "client/io/medit_format.h"
#include "client/io/nifti_writer.h"
#include "client/io/vtk_legacy_format.h"
#include "client/io/vtu_format.h"
#include "client/io/zlib_codec.h"
#include "core/refine.h"
#include "wire/conversion.h"
#include "wire/request_writer.h"
#include "wire/response_writer.h"

namespace tetrefine::fuzz {
namespace {

std::filesystem::path root;

void Write(const std::string& target, const std::string& name, const std::string& bytes) {
  const std::filesystem::path dir = root / target;
  std::filesystem::create_directories(dir);
  std::ofstream out(dir / ("seed-" + name), std::ios::binary);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  if (!out) {
    std::fprintf(stderr, "cannot write %s\n", (dir / name).c_str());
    std::exit(1);
  }
}

Volume SmallVolume(VoxelType type, const Index3& dims, const Index3& lo, const Index3& hi) {
  const GridGeometry grid{.dims = dims, .origin = {0.0, 0.0, 0.0}, .spacing = {1.0, 1.0, 1.0}};
  std::vector<std::byte> data;
  for (int64_t k = lo[2]; k < hi[2]; ++k) {
    for (int64_t j = lo[1]; j < hi[1]; ++j) {
      for (int64_t i = lo[0]; i < hi[0]; ++i) {
        const double v = 20.0 * std::sin(0.9 * i) * std::cos(0.7 * j) + 3.0 * k;
        auto put = [&](auto x) {
          const auto* b = reinterpret_cast<const std::byte*>(&x);
          data.insert(data.end(), b, b + sizeof(x));
        };
        switch (type) {
          case VoxelType::kUint8:
            put(static_cast<uint8_t>(v + 40));
            break;
          case VoxelType::kInt16:
            put(static_cast<int16_t>(v));
            break;
          case VoxelType::kUint16:
            put(static_cast<uint16_t>(v + 40));
            break;
          case VoxelType::kInt32:
            put(static_cast<int32_t>(v));
            break;
          case VoxelType::kFloat32:
            put(static_cast<float>(v));
            break;
          case VoxelType::kFloat64:
            put(v);
            break;
        }
      }
    }
  }
  return *Volume::Create(grid, lo, hi, type, std::move(data));
}

// One cube cell [1, 3]^3 of 5 positive tets.
Mesh CubeMesh() {
  Mesh mesh;
  for (int b = 0; b < 8; ++b) {
    mesh.points.push_back({1.0 + 2.0 * (b & 1), 1.0 + 2.0 * ((b >> 1) & 1), 1.0 + 2.0 * (b >> 2)});
  }
  const uint32_t corners[4] = {0, 3, 5, 6};
  for (uint32_t c : corners) mesh.tets.push_back({c, c ^ 1u, c ^ 2u, c ^ 4u});
  mesh.tets.push_back({1, 2, 4, 7});
  for (Tet& t : mesh.tets) {
    if (SignedVolume6(mesh.points[t[0]], mesh.points[t[1]], mesh.points[t[2]], mesh.points[t[3]]) <
        0) {
      std::swap(t[2], t[3]);
    }
  }
  return mesh;
}

// A request stream in the request target's framing: 2-byte length, message, repeated.
std::string Framed(const wire::RequestOptions& options, const Volume& volume, const Mesh& mesh,
                   size_t chunk_bytes) {
  std::string out;
  wire::WriteRequest(options, volume, mesh, chunk_bytes, [&](const v1::RefineRequest& r) {
    const std::string bytes = r.SerializeAsString();
    out.push_back(static_cast<char>(bytes.size() & 0xff));
    out.push_back(static_cast<char>(bytes.size() >> 8));
    out += bytes;
    return true;
  });
  return out;
}

void RequestSeeds() {
  const Mesh mesh = CubeMesh();
  wire::RequestOptions options;
  options.refine.epsilon = 0.05;
  options.refine.max_iterations = 2;
  options.refine.lattice_n = 2;
  Write(
      "request", "float64-whole",
      Framed(options, SmallVolume(VoxelType::kFloat64, {5, 5, 5}, {0, 0, 0}, {5, 5, 5}), mesh, 64));
  options.stream_every_iteration = true;
  options.response_chunk_bytes = 300;
  Write(
      "request", "int16-slab",
      Framed(options, SmallVolume(VoxelType::kInt16, {6, 6, 6}, {1, 0, 1}, {5, 5, 5}), mesh, 100));
  options = {};
  options.skip_final_mesh = true;
  options.refine.orientation = OrientationPolicy::kNormalize;
  options.refine.outside = OutsidePolicy::kClamp;
  options.refine.min_edge_length = 0.0;
  options.refine.norm_coeff = 10.0;
  options.SetMaxTets(200);
  Mesh with_values = mesh;
  for (size_t i = 0; i < mesh.points.size(); ++i) with_values.values.push_back(0.5 * i);
  std::swap(with_values.tets[0][2], with_values.tets[0][3]);
  Write("request", "uint8-values-normalize",
        Framed(options, SmallVolume(VoxelType::kUint8, {5, 5, 5}, {0, 0, 0}, {5, 5, 5}),
               with_values, 1 << 20));
}

// What a server answers for the cube: statistics, every iteration's mesh, the final mesh and the
// summary, in 300-byte chunks. First byte: the final mesh was asked for.
void ResponseSeeds() {
  const Volume volume = SmallVolume(VoxelType::kFloat64, {5, 5, 5}, {0, 0, 0}, {5, 5, 5});
  RefineOptions options;
  options.epsilon = 0.05;
  options.max_iterations = 2;
  std::string out(1, '\1');
  wire::ResponseWriter writer(300, [&](const v1::RefineResponse& r) {
    const std::string bytes = r.SerializeAsString();
    out.push_back(static_cast<char>(bytes.size() & 0xff));
    out.push_back(static_cast<char>(bytes.size() >> 8));
    out += bytes;
    return true;
  });
  options.on_iteration = [&](const IterationStats& stats, const Mesh& mesh) {
    writer.WriteIterationStats(stats);
    writer.WriteMesh(stats.iteration, false, mesh, {}, {});
  };
  const RefineResult result = *Refine(volume, CubeMesh(), options);
  writer.WriteMesh(static_cast<int>(result.iterations.size()), true, result.mesh,
                   result.tet_iteration, result.tet_quality);
  writer.WriteSummary(result, {}, 5);
  Write("response", "cube-every-iteration", out);
}

void RefineSeeds() {
  std::mt19937 rng(7);
  for (int n : {0, 24, 96, 200, 400}) {
    std::string bytes(n, '\0');
    for (char& c : bytes) c = static_cast<char>(rng());
    Write("refine", "random-" + std::to_string(n), bytes);
  }
}

void MeshSeeds() {
  io::MeshFile file;
  file.mesh = CubeMesh();
  for (size_t i = 0; i < file.mesh.points.size(); ++i) file.mesh.values.push_back(1.5 * i - 2);
  for (size_t t = 0; t < file.mesh.tets.size(); ++t) {
    file.tet_iteration.push_back(static_cast<int32_t>(t % 3));
    file.tet_quality.push_back(0.25f + 0.1f * static_cast<float>(t));
  }
  Write("vtu", "cube", io::FormatVtu(file));
  Write("vtk_legacy", "cube", io::FormatVtkLegacy(file));
  Write("gmsh", "cube", io::FormatGmsh41(file));
  Write("medit", "cube", io::FormatMedit(file));
}

void NiftiSeeds() {
  const std::filesystem::path tmp = std::filesystem::temp_directory_path() / "tetrefine-seeds.nii";
  int index = 0;
  for (VoxelType type : {VoxelType::kInt16, VoxelType::kFloat32}) {
    for (int version : {1, 2}) {
      const Volume volume = SmallVolume(type, {3, 4, 2}, {0, 0, 0}, {3, 4, 2});
      if (!io::WriteNifti(tmp.string(), volume, {.version = version}).ok()) std::exit(1);
      std::ifstream in(tmp, std::ios::binary);
      const std::string bytes((std::istreambuf_iterator<char>(in)),
                              std::istreambuf_iterator<char>());
      // Mode bytes of the target: 0 as is, 1 gzip-compressed by the target, 2 split .hdr/.img.
      const int mode = index++ % 3;
      Write("nifti", "v" + std::to_string(version) + "-" + std::string(VoxelTypeName(type)),
            std::string(1, static_cast<char>(mode)) + bytes);
      if (mode == 0)
        Write("nifti", "gzip-v" + std::to_string(version),
              std::string(1, '\0') + *io::GzipCompress(bytes));
    }
  }
  std::filesystem::remove(tmp);
}

}  // namespace
}  // namespace tetrefine::fuzz

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: %s <repo>/fuzz/corpus\n", argv[0]);
    return 2;
  }
  tetrefine::fuzz::root = argv[1];
  tetrefine::fuzz::RequestSeeds();
  tetrefine::fuzz::ResponseSeeds();
  tetrefine::fuzz::RefineSeeds();
  tetrefine::fuzz::MeshSeeds();
  tetrefine::fuzz::NiftiSeeds();
  return 0;
}
