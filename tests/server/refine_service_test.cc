// A real server on a loopback port gives exactly what core Refine gives.

#include <chrono>
#include <thread>
#include <utility>
#include <vector>

#include "client/refine_client.h"
#include "gtest/gtest.h"
#include "server/embedded_server.h"
#include "tests/support/geometry.h"
#include "tests/support/loopback_server.h"
#include "tests/support/result_compare.h"

namespace tetrefine::testing {
namespace {

constexpr Index3 kDims{14, 13, 12};

RefineOptions CoreOptions(double epsilon) {
  RefineOptions options;
  options.epsilon = epsilon;
  options.max_iterations = 6;
  options.lattice_n = 4;
  return options;
}

struct Case {
  Volume volume = TestVolume(kDims);
  Mesh mesh = FiveTetMesh({1.0, 1.5, 1.0}, {11.0, 10.5, 10.0}, {4, 3, 3});
};

RefineResult CoreRefine(const Volume& volume, const Mesh& mesh, const RefineOptions& options) {
  absl::StatusOr<RefineResult> result = Refine(volume, mesh, options);
  EXPECT_TRUE(result.ok()) << result.status();
  return *std::move(result);
}

client::ClientResult ServiceRefine(const std::shared_ptr<grpc::Channel>& channel,
                                   const Volume& volume, const Mesh& mesh,
                                   const client::RefineRequestOptions& options,
                                   const client::RefineCallbacks& callbacks = {},
                                   const client::CallOptions& call = {}) {
  absl::StatusOr<client::ClientResult> result =
      client::RefineViaService(channel, volume, mesh, options, callbacks, call);
  EXPECT_TRUE(result.ok()) << result.status();
  return result.ok() ? *std::move(result) : client::ClientResult{};
}

client::CallOptions Chunks(size_t bytes) {
  client::CallOptions call;
  call.chunk_bytes = bytes;
  return call;
}

class ServiceRefineTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() { server_ = new LoopbackServer(); }
  static void TearDownTestSuite() {
    delete server_;
    server_ = nullptr;
  }
  static LoopbackServer* server_;
};
LoopbackServer* ServiceRefineTest::server_ = nullptr;

TEST_F(ServiceRefineTest, MatchesCoreBitwise) {
  const Case c;
  const RefineOptions options = CoreOptions(0.02);
  const RefineResult expected = CoreRefine(c.volume, c.mesh, options);
  ASSERT_GE(expected.iterations.size(), 2u) << "the case should refine a few times";

  std::vector<IterationStats> streamed;
  client::RefineCallbacks callbacks;
  callbacks.on_iteration = [&](const IterationStats& s) { streamed.push_back(s); };
  const client::ClientResult actual = ServiceRefine(
      server_->NewChannel(), c.volume, c.mesh, wire::RequestOptionsFromCore(options), callbacks);
  ExpectSameResult(expected, actual.result);
  ASSERT_EQ(streamed.size(), expected.iterations.size());
  for (size_t i = 0; i < streamed.size(); ++i) ExpectSameStats(expected.iterations[i], streamed[i]);
  EXPECT_EQ(actual.service.max_tets, options.max_tets);
  EXPECT_GE(actual.service.total_seconds, actual.service.input_seconds);
}

TEST_F(ServiceRefineTest, OddChunkSizesReassembleIdentically) {
  const Case c;
  const RefineOptions options = CoreOptions(0.03);
  const RefineResult expected = CoreRefine(c.volume, c.mesh, options);
  for (const auto& [request_bytes, response_bytes] :
       std::vector<std::pair<size_t, uint32_t>>{{7, 300}, {1000, 1000}, {1, 257}, {5000, 0}}) {
    SCOPED_TRACE(::testing::Message() << "request chunks of " << request_bytes
                                      << " B, response chunks of " << response_bytes << " B");
    client::RefineRequestOptions request = wire::RequestOptionsFromCore(options);
    request.response_chunk_bytes = response_bytes;
    const client::ClientResult actual =
        ServiceRefine(server_->NewChannel(), c.volume, c.mesh, request, {}, Chunks(request_bytes));
    ExpectSameResult(expected, actual.result);
  }
}

TEST_F(ServiceRefineTest, StreamsEveryIterationsMeshWhenAsked) {
  const Case c;
  RefineOptions options = CoreOptions(0.02);
  std::vector<Mesh> core_meshes;
  options.on_iteration = [&](const IterationStats&, const Mesh& mesh) {
    core_meshes.push_back(mesh);
  };
  const RefineResult expected = CoreRefine(c.volume, c.mesh, options);

  std::vector<std::pair<int, Mesh>> meshes;
  client::RefineCallbacks callbacks;
  callbacks.on_mesh = [&](int iteration, const Mesh& mesh) {
    meshes.emplace_back(iteration, mesh);
  };
  client::RefineRequestOptions request = wire::RequestOptionsFromCore(options);
  request.response_chunk_bytes = 512;
  const client::ClientResult actual =
      ServiceRefine(server_->NewChannel(), c.volume, c.mesh, request, callbacks);
  ExpectSameResult(expected, actual.result);
  ASSERT_EQ(meshes.size(), core_meshes.size());
  for (size_t i = 0; i < meshes.size(); ++i) {
    EXPECT_EQ(meshes[i].first, static_cast<int>(i) + 1);
    ExpectSameMesh(core_meshes[i], meshes[i].second);
  }
}

TEST_F(ServiceRefineTest, SkipsTheFinalMeshWhenAsked) {
  const Case c;
  const RefineOptions options = CoreOptions(0.03);
  const RefineResult expected = CoreRefine(c.volume, c.mesh, options);
  client::RefineRequestOptions request = wire::RequestOptionsFromCore(options);
  request.skip_final_mesh = true;
  const client::ClientResult actual =
      ServiceRefine(server_->NewChannel(), c.volume, c.mesh, request);
  EXPECT_TRUE(actual.result.mesh.tets.empty());
  ASSERT_EQ(actual.result.iterations.size(), expected.iterations.size());
  EXPECT_EQ(actual.result.stop_reason, expected.stop_reason);
}

TEST_F(ServiceRefineTest, EveryVoxelTypeMatchesCore) {
  const Mesh mesh = FiveTetMesh({1.0, 1.5, 1.0}, {11.0, 10.5, 10.0}, {3, 3, 2});
  for (VoxelType type : {VoxelType::kUint8, VoxelType::kInt16, VoxelType::kUint16,
                         VoxelType::kInt32, VoxelType::kFloat32, VoxelType::kFloat64}) {
    SCOPED_TRACE(std::string(VoxelTypeName(type)));
    const Volume volume = TestVolume(kDims, type);
    const RefineOptions options = CoreOptions(0.03);
    const RefineResult expected = CoreRefine(volume, mesh, options);
    const client::ClientResult actual =
        ServiceRefine(server_->NewChannel(), volume, mesh, wire::RequestOptionsFromCore(options),
                      {}, Chunks(333));
    ExpectSameResult(expected, actual.result);
  }
}

TEST_F(ServiceRefineTest, SlabCoveringTheMeshGivesTheWholeVolumesBits) {
  const Case c;
  const std::array<double, 2> range = c.volume.ValueRange();
  RefineOptions options = CoreOptions(0.02);
  options.norm_coeff = range[1] - range[0];
  const RefineResult expected = CoreRefine(c.volume, c.mesh, options);

  // The mesh spans [1, 11] x [1.5, 10.5] x [1, 10]: samples 1..11, 1..11, 1..10 cover it.
  const Volume slab = TestSlab(kDims, {1, 1, 1}, {12, 12, 11});
  const client::ClientResult actual =
      ServiceRefine(server_->NewChannel(), slab, c.mesh, wire::RequestOptionsFromCore(options));
  ExpectSameResult(expected, actual.result);
}

TEST_F(ServiceRefineTest, ConcurrentClientsGetIndependentResults) {
  const Case c;
  const std::vector<double> epsilons = {0.02, 0.03, 0.05, 0.08};
  std::vector<RefineResult> expected;
  for (double e : epsilons) expected.push_back(CoreRefine(c.volume, c.mesh, CoreOptions(e)));

  std::vector<client::ClientResult> actual(epsilons.size());
  {
    std::vector<std::jthread> clients;
    for (size_t i = 0; i < epsilons.size(); ++i) {
      clients.emplace_back([&, i] {
        actual[i] =
            ServiceRefine(server_->NewChannel(), c.volume, c.mesh,
                          wire::RequestOptionsFromCore(CoreOptions(epsilons[i])), {}, Chunks(4096));
      });
    }
  }
  for (size_t i = 0; i < epsilons.size(); ++i) {
    SCOPED_TRACE(::testing::Message() << "epsilon " << epsilons[i]);
    ExpectSameResult(expected[i], actual[i].result);
  }
}

TEST_F(ServiceRefineTest, TetBudgetDefaultsToTheServersLimit) {
  server::ServiceConfig config;
  config.limits.max_output_tets = 1500;
  LoopbackServer small(config);
  const Case c;
  RefineOptions options = CoreOptions(0.01);
  options.max_tets = 1500;
  const RefineResult expected = CoreRefine(c.volume, c.mesh, options);
  ASSERT_EQ(expected.stop_reason, StopReason::kTetBudget);
  ASSERT_GE(expected.iterations.size(), 1u);

  client::RefineRequestOptions request = wire::RequestOptionsFromCore(options);
  request.send_max_tets = false;
  const client::ClientResult actual = ServiceRefine(small.NewChannel(), c.volume, c.mesh, request);
  ExpectSameResult(expected, actual.result);
  EXPECT_EQ(actual.service.max_tets, 1500);
}

TEST_F(ServiceRefineTest, EmbeddedServerMatchesCore) {
  absl::StatusOr<std::unique_ptr<server::EmbeddedServer>> embedded =
      server::EmbeddedServer::Start();
  ASSERT_TRUE(embedded.ok()) << embedded.status();
  const Case c;
  const RefineOptions options = CoreOptions(0.02);
  const RefineResult expected = CoreRefine(c.volume, c.mesh, options);
  const client::ClientResult actual = ServiceRefine((*embedded)->Channel(), c.volume, c.mesh,
                                                    wire::RequestOptionsFromCore(options));
  ExpectSameResult(expected, actual.result);
}

TEST_F(ServiceRefineTest, ReportsHealthAndServerInfo) {
  const auto deadline = std::chrono::system_clock::now() + std::chrono::seconds(10);
  absl::StatusOr<client::ServingStatus> health =
      client::CheckHealth(server_->NewChannel(), "", deadline);
  ASSERT_TRUE(health.ok()) << health.status();
  EXPECT_EQ(*health, client::ServingStatus::kServing);
  health = client::CheckHealth(server_->NewChannel(), "tetrefine.v1.Refiner", deadline);
  ASSERT_TRUE(health.ok()) << health.status();
  EXPECT_EQ(*health, client::ServingStatus::kServing);
  health = client::CheckHealth(server_->NewChannel(), "no.such.Service", deadline);
  EXPECT_EQ(health.status().code(), absl::StatusCode::kNotFound) << health.status();

  absl::StatusOr<client::ServerInfo> info = client::GetServerInfo(server_->NewChannel(), deadline);
  ASSERT_TRUE(info.ok()) << info.status();
  EXPECT_FALSE(info->version.empty());
  const wire::ServiceLimits defaults;
  EXPECT_EQ(info->limits.max_voxels, defaults.max_voxels);
  EXPECT_EQ(info->limits.max_input_tets, defaults.max_input_tets);
  EXPECT_EQ(info->limits.max_output_tets, defaults.max_output_tets);
  EXPECT_EQ(info->limits.max_concurrent_refinements, defaults.max_concurrent_refinements);
  EXPECT_EQ(info->limits.max_message_bytes, defaults.max_message_bytes);
}

}  // namespace
}  // namespace tetrefine::testing
