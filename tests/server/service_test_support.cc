#include "tests/server/service_test_support.h"

#include <algorithm>
#include <atomic>
#include <bit>
#include <chrono>
#include <cmath>
#include <cstring>
#include <string>
#include <utility>

#include "gtest/gtest.h"
#include "server/server_setup.h"
#include "tetrefine/v1/tetrefine.grpc.pb.h"

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

// Bit patterns, so that -0.0 != 0.0 and NaN == NaN: "identical" means identical.
template <typename T>
bool SameBits(const std::vector<T>& a, const std::vector<T>& b) {
  return a.size() == b.size() &&
         (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(T)) == 0);
}

void ExpectSameDouble(double expected, double actual, const char* what) {
  EXPECT_EQ(std::bit_cast<uint64_t>(expected), std::bit_cast<uint64_t>(actual))
      << what << ": expected " << expected << ", got " << actual;
}

void ExpectSameQuality(const QualityStats& e, const QualityStats& a, const char* what) {
  ExpectSameDouble(e.min, a.min, what);
  ExpectSameDouble(e.mean, a.mean, what);
  EXPECT_EQ(e.count, a.count) << what;
}

}  // namespace

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
  EXPECT_TRUE(volume.ok()) << volume.status();
  return *std::move(volume);
}

Volume TestVolume(const Index3& dims, VoxelType type) {
  return TestSlab(dims, {0, 0, 0}, dims, type);
}

Mesh FiveTetMesh(const Vec3& lo, const Vec3& hi, const std::array<int, 3>& cells) {
  Mesh mesh;
  const int nx = cells[0] + 1, ny = cells[1] + 1;
  auto vertex = [&](int i, int j, int k) { return static_cast<uint32_t>(i + nx * (j + ny * k)); };
  for (int k = 0; k <= cells[2]; ++k) {
    for (int j = 0; j <= cells[1]; ++j) {
      for (int i = 0; i <= cells[0]; ++i) {
        mesh.points.push_back({lo[0] + (hi[0] - lo[0]) * i / cells[0],
                               lo[1] + (hi[1] - lo[1]) * j / cells[1],
                               lo[2] + (hi[2] - lo[2]) * k / cells[2]});
      }
    }
  }
  // Corners by bits (x, y, z). Even cells cut off the corners of even bit count, odd cells the
  // others, so the face diagonals of neighbouring cells coincide.
  for (int k = 0; k < cells[2]; ++k) {
    for (int j = 0; j < cells[1]; ++j) {
      for (int i = 0; i < cells[0]; ++i) {
        uint32_t c[8];
        for (int b = 0; b < 8; ++b) c[b] = vertex(i + (b & 1), j + ((b >> 1) & 1), k + (b >> 2));
        const bool even = (i + j + k) % 2 == 0;
        const int corners[4] = {even ? 0 : 1, even ? 3 : 2, even ? 5 : 4, even ? 6 : 7};
        std::vector<Tet> tets;
        for (int corner : corners) {
          tets.push_back({c[corner], c[corner ^ 1], c[corner ^ 2], c[corner ^ 4]});
        }
        const int center[4] = {even ? 1 : 0, even ? 2 : 3, even ? 4 : 5, even ? 7 : 6};
        tets.push_back({c[center[0]], c[center[1]], c[center[2]], c[center[3]]});
        for (Tet& t : tets) {
          if (SignedVolume6(mesh.points[t[0]], mesh.points[t[1]], mesh.points[t[2]],
                            mesh.points[t[3]]) < 0) {
            std::swap(t[2], t[3]);
          }
          mesh.tets.push_back(t);
        }
      }
    }
  }
  return mesh;
}

LoopbackServer::LoopbackServer(const server::ServiceConfig& config) {
  server::InitGrpcFeatures();  // before the builder exists
  service_ = std::make_unique<server::RefinerService>(config);
  grpc::ServerBuilder builder;
  builder.AddListeningPort("127.0.0.1:0", grpc::InsecureServerCredentials(), &port_);
  server_ = server::StartServer(config, service_.get(), &builder);
  EXPECT_NE(server_, nullptr);
  EXPECT_NE(port_, 0);
}

LoopbackServer::~LoopbackServer() {
  server_->Shutdown(std::chrono::system_clock::now());
  server_->Wait();
}

std::shared_ptr<grpc::Channel> LoopbackServer::NewChannel() const {
  // Distinct channel arguments give each channel its own connection, as separate clients have.
  static std::atomic<int> channels{0};
  grpc::ChannelArguments args;
  args.SetInt("tetrefine.test.channel", channels.fetch_add(1));
  std::shared_ptr<grpc::Channel> channel = grpc::CreateCustomChannel(
      "127.0.0.1:" + std::to_string(port_), grpc::InsecureChannelCredentials(), args);
  // Connected up front: a first connection attempt on a busy loopback occasionally fails
  // transiently, and calls are fail-fast.
  EXPECT_TRUE(
      channel->WaitForConnected(std::chrono::system_clock::now() + std::chrono::seconds(10)));
  return channel;
}

grpc::Status SendRaw(const std::shared_ptr<grpc::Channel>& channel,
                     const std::vector<v1::RefineRequest>& requests) {
  v1::Refiner::Stub stub(channel);
  grpc::ClientContext context;
  context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(60));
  auto stream = stub.Refine(&context);
  for (const v1::RefineRequest& r : requests) {
    if (!stream->Write(r)) break;
  }
  stream->WritesDone();
  v1::RefineResponse response;
  while (stream->Read(&response)) {
  }
  return stream->Finish();
}

void ExpectSameMesh(const Mesh& expected, const Mesh& actual) {
  EXPECT_EQ(expected.points.size(), actual.points.size());
  EXPECT_EQ(expected.tets.size(), actual.tets.size());
  EXPECT_TRUE(SameBits(expected.points, actual.points)) << "points differ";
  EXPECT_TRUE(SameBits(expected.tets, actual.tets)) << "tets differ";
  EXPECT_TRUE(SameBits(expected.values, actual.values)) << "values differ";
}

void ExpectSameStats(const IterationStats& e, const IterationStats& a) {
  EXPECT_EQ(e.iteration, a.iteration);
  EXPECT_EQ(e.initial_tets, a.initial_tets);
  EXPECT_EQ(e.final_tets, a.final_tets);
  EXPECT_EQ(e.tets_with_error, a.tets_with_error);
  EXPECT_EQ(e.edges, a.edges);
  EXPECT_EQ(e.split_edges, a.split_edges);
  EXPECT_EQ(e.short_edges_kept, a.short_edges_kept);
  ExpectSameDouble(e.max_error, a.max_error, "max_error");
  ExpectSameDouble(e.mean_error, a.mean_error, "mean_error");
  EXPECT_EQ(e.configurations, a.configurations);
  EXPECT_EQ(e.schonhardt_prisms, a.schonhardt_prisms);
  ExpectSameQuality(e.quality, a.quality, "quality");
}

void ExpectSameResult(const RefineResult& e, const RefineResult& a) {
  ExpectSameMesh(e.mesh, a.mesh);
  EXPECT_TRUE(SameBits(e.tet_iteration, a.tet_iteration)) << "tet_iteration differs";
  EXPECT_TRUE(SameBits(e.tet_quality, a.tet_quality)) << "tet_quality differs";
  ASSERT_EQ(e.iterations.size(), a.iterations.size());
  for (size_t i = 0; i < e.iterations.size(); ++i)
    ExpectSameStats(e.iterations[i], a.iterations[i]);
  EXPECT_EQ(e.stop_reason, a.stop_reason);
  EXPECT_EQ(e.next_iteration_tets, a.next_iteration_tets);
  ExpectSameDouble(e.next_iteration_min_quality, a.next_iteration_min_quality,
                   "next_iteration_min_quality");
  ExpectSameDouble(e.final_max_error, a.final_max_error, "final_max_error");
  ExpectSameDouble(e.final_mean_error, a.final_mean_error, "final_mean_error");
  ExpectSameDouble(e.norm_coeff, a.norm_coeff, "norm_coeff");
  ExpectSameQuality(e.initial_quality, a.initial_quality, "initial_quality");
  ExpectSameQuality(e.final_quality, a.final_quality, "final_quality");
  EXPECT_EQ(e.lattice.n, a.lattice.n);
  EXPECT_EQ(e.lattice.tets_sampled, a.lattice.tets_sampled);
  EXPECT_EQ(e.lattice.points_sampled, a.lattice.points_sampled);
  ExpectSameDouble(e.lattice.max_error, a.lattice.max_error, "lattice.max_error");
  ExpectSameDouble(e.lattice.mean_error, a.lattice.mean_error, "lattice.mean_error");
  ExpectSameDouble(e.lattice.share_above_epsilon, a.lattice.share_above_epsilon,
                   "lattice.share_above_epsilon");
  ExpectSameDouble(e.lattice.volume_mean_error, a.lattice.volume_mean_error,
                   "lattice.volume_mean_error");
  ExpectSameDouble(e.lattice.volume_share_above_epsilon, a.lattice.volume_share_above_epsilon,
                   "lattice.volume_share_above_epsilon");
  EXPECT_EQ(e.tets_reoriented, a.tets_reoriented);
}

}  // namespace tetrefine::testing
