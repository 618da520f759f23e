#include "tests/support/geometry.h"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <utility>

#include "core/five_tet_cell.h"
#include "core/quality.h"

namespace tetrefine::testing {
namespace {

template <typename T>
void Append(std::vector<std::byte>& out, T value) {
  const auto* bytes = reinterpret_cast<const std::byte*>(&value);
  out.insert(out.end(), bytes, bytes + sizeof(T));
}

void AppendAs(VoxelType type, double v, std::vector<std::byte>& out) {
  switch (type) {
    case VoxelType::kUint8:
      return Append(out,
                    static_cast<uint8_t>(std::lround(std::clamp(v * 100.0 + 128, 0.0, 255.0))));
    case VoxelType::kInt16:
      return Append(out, static_cast<int16_t>(std::lround(v * 100.0)));
    case VoxelType::kUint16:
      return Append(out, static_cast<uint16_t>(std::lround(v * 100.0 + 1000.0)));
    case VoxelType::kInt32:
      return Append(out, static_cast<int32_t>(std::lround(v * 100.0)));
    case VoxelType::kFloat32:
      return Append(out, static_cast<float>(v));
    case VoxelType::kFloat64:
      return Append(out, v);
  }
}

}  // namespace

std::vector<uint64_t> Seeds(int count) {
  if (const char* pinned = std::getenv("TETREFINE_SEED")) {
    return {std::stoull(pinned)};
  }
  std::vector<uint64_t> seeds;
  for (int i = 0; i < count; ++i) seeds.push_back(20261122 + 7919 * static_cast<uint64_t>(i));
  return seeds;
}

std::array<Vec3, 4> RandomTet(std::mt19937_64& rng, double min_quality) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (;;) {
    std::array<Vec3, 4> p;
    for (auto& q : p) q = {u(rng), u(rng), u(rng)};
    if (MeanRatio(p[0], p[1], p[2], p[3]) < min_quality) continue;
    if (SignedVolume6(p[0], p[1], p[2], p[3]) < 0) std::swap(p[2], p[3]);
    return p;
  }
}

std::set<std::pair<uint32_t, uint32_t>> UniqueEdges(const std::vector<Tet>& tets) {
  std::set<std::pair<uint32_t, uint32_t>> edges;
  for (const Tet& t : tets) {
    for (int i = 0; i < 4; ++i) {
      for (int j = i + 1; j < 4; ++j) edges.insert(std::minmax(t[i], t[j]));
    }
  }
  return edges;
}

Mat3 RandomRotation(std::mt19937_64& rng, bool mirror) {
  std::normal_distribution<double> n(0.0, 1.0);
  double q[4] = {n(rng), n(rng), n(rng), n(rng)};
  const double len = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
  for (double& x : q) x /= len;
  const double a = q[0], b = q[1], c = q[2], d = q[3];
  Mat3 r{
      a * a + b * b - c * c - d * d, 2 * (b * c - a * d),           2 * (b * d + a * c),
      2 * (b * c + a * d),           a * a + c * c - b * b - d * d, 2 * (c * d - a * b),
      2 * (b * d - a * c),           2 * (c * d + a * b),           a * a + d * d - b * b - c * c};
  if (mirror) {
    for (int row = 0; row < 3; ++row) r[3 * row] = -r[3 * row];
  }
  return r;
}

Mesh FiveTetMesh(const Vec3& lo, const Vec3& hi, const std::array<int, 3>& cells) {
  Mesh m;
  const int nx = cells[0] + 1, ny = cells[1] + 1, nz = cells[2] + 1;
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i)
        m.points.push_back({lo[0] + (hi[0] - lo[0]) * i / cells[0],
                            lo[1] + (hi[1] - lo[1]) * j / cells[1],
                            lo[2] + (hi[2] - lo[2]) * k / cells[2]});
  auto id = [&](int i, int j, int k) { return static_cast<uint32_t>(i + nx * (j + ny * k)); };
  for (int k = 0; k < cells[2]; ++k)
    for (int j = 0; j < cells[1]; ++j)
      for (int i = 0; i < cells[0]; ++i) {
        std::array<uint32_t, 8> c;
        for (int b = 0; b < 8; ++b) c[b] = id(i + (b & 1), j + ((b >> 1) & 1), k + ((b >> 2) & 1));
        AppendFiveTetCell(c, (i + j + k) % 2 == 0, m.points, &m.tets);
      }
  return m;
}

double TestField(const Vec3& p) {
  return std::sin(0.45 * p[0]) * std::cos(0.35 * p[1]) + 0.02 * p[2] * p[2] +
         0.3 * std::sin(0.8 * p[1] + 0.6 * p[2]);
}

Volume TestSlab(const Index3& dims, const Index3& lo, const Index3& hi, VoxelType type) {
  const GridGeometry grid{.dims = dims, .origin = {0.0, 0.0, 0.0}, .spacing = {1.0, 1.0, 1.0}};
  std::vector<std::byte> data;
  for (int64_t k = lo[2]; k < hi[2]; ++k) {
    for (int64_t j = lo[1]; j < hi[1]; ++j) {
      for (int64_t i = lo[0]; i < hi[0]; ++i) {
        AppendAs(
            type,
            TestField({static_cast<double>(i), static_cast<double>(j), static_cast<double>(k)}),
            data);
      }
    }
  }
  absl::StatusOr<Volume> volume = Volume::Create(grid, lo, hi, type, std::move(data));
  if (!volume.ok()) {
    // A test that asks for an impossible slab is broken; no test can go on from here.
    std::fprintf(stderr, "TestSlab: %s\n", std::string(volume.status().message()).c_str());
    std::abort();
  }
  return *std::move(volume);
}

Volume TestVolume(const Index3& dims, VoxelType type) {
  return TestSlab(dims, {0, 0, 0}, dims, type);
}

}  // namespace tetrefine::testing
