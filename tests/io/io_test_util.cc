#include "tests/io/io_test_util.h"

#include <unistd.h>

#include <atomic>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <random>
#include <sstream>

#include "gtest/gtest.h"

namespace tetrefine::io::iotest {

ScratchDir::ScratchDir() {
  static std::atomic<int> counter{0};
  path_ = (std::filesystem::path(::testing::TempDir()) /
           ("tetrefine_io_" + std::to_string(getpid()) + "_" + std::to_string(counter++)))
              .string();
  std::filesystem::remove_all(path_);
  std::filesystem::create_directories(path_);
}

ScratchDir::~ScratchDir() {
  std::error_code ec;
  std::filesystem::remove_all(path_, ec);
}

std::string ScratchDir::File(const std::string& name) const { return path_ + "/" + name; }

void WriteBytes(const std::string& path, const std::string& bytes) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  ASSERT_TRUE(out.good()) << "cannot write " << path;
}

std::string ReadBytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream buffer;
  buffer << in.rdbuf();
  return buffer.str();
}

MeshFile RandomMesh(uint64_t seed, const RandomMeshOptions& options) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  std::uniform_int_distribution<int> exponent(-300, 12);
  std::uniform_int_distribution<int> kind(0, 9);
  const auto awkward = [&]() {
    switch (kind(rng)) {
      case 0:
        return 0.0;
      case 1:
        return unit(rng) * std::pow(10.0, exponent(rng));
      case 2:
        return 0.1 * std::floor(unit(rng) * 100);
      default:
        return unit(rng) * 100.0;
    }
  };
  MeshFile file;
  file.mesh.points.resize(options.vertices);
  for (Vec3& p : file.mesh.points) p = {awkward(), awkward(), awkward()};
  std::uniform_int_distribution<uint32_t> vertex(0, options.vertices - 1);
  for (int t = 0; t < options.tets; ++t) {
    Tet tet;
    for (int k = 0; k < 4; ++k) {
      bool repeated;
      do {
        tet[k] = vertex(rng);
        repeated = false;
        for (int m = 0; m < k; ++m) repeated = repeated || tet[m] == tet[k];
      } while (repeated && options.vertices >= 4);
    }
    file.mesh.tets.push_back(tet);
  }
  if (options.values) {
    for (int i = 0; i < options.vertices; ++i) file.mesh.values.push_back(awkward());
  }
  std::uniform_int_distribution<int32_t> iteration(-5, 1 << 30);
  for (int t = 0; t < options.tets; ++t) {
    if (options.iteration) file.tet_iteration.push_back(t % 3 == 0 ? t % 7 : iteration(rng));
    if (options.quality) file.tet_quality.push_back(static_cast<float>(awkward() / 3.0));
  }
  if (options.labels) {
    // Mostly a few small region numbers, as real meshes have, and some extremes.
    std::uniform_int_distribution<int32_t> any(std::numeric_limits<int32_t>::min(),
                                               std::numeric_limits<int32_t>::max());
    for (int t = 0; t < options.tets; ++t) {
      file.mesh.labels.push_back(t % 11 == 5 ? any(rng) : static_cast<int32_t>(rng() % 4));
    }
    file.label_name = options.label_name;
  }
  file.frame = options.frame;
  return file;
}

std::string SharedData(const std::string& name) {
  return std::string(TETREFINE_SHARED_DATA_DIR) + "/" + name;
}

std::string MeshFixture(const std::string& name) {
  return std::string(TETREFINE_SOURCE_DIR) + "/tests/data/meshes/" + name;
}

std::map<int32_t, double> RegionVolumes(const MeshFile& file) {
  std::map<int32_t, double> volume;
  for (size_t t = 0; t < file.mesh.tets.size(); ++t) {
    const Tet& k = file.mesh.tets[t];
    const auto& p = file.mesh.points;
    volume[file.mesh.labels[t]] += SignedVolume6(p[k[0]], p[k[1]], p[k[2]], p[k[3]]) / 6.0;
  }
  return volume;
}

}  // namespace tetrefine::io::iotest
