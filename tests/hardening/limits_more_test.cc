// Limits on what a caller controls that tests/server does not cover, against a real
// tetrefine_server process: the response chunk size a caller asks for is clamped both ways, an
// absurd iteration count is harmless (work stays bounded by the tet budget and convergence), and
// declared sizes within the limits that a memory-limited server cannot hold are refused by name,
// an address-space limit sizes the tet budget, and a call that runs out of memory ends alone.

#include <unistd.h>

#include <algorithm>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "client/refine_client.h"
#include "gmock/gmock.h"
#include "gtest/gtest.h"
#include "tests/hardening/workloads.h"
#include "tests/support/geometry.h"
#include "tests/support/loopback_server.h"
#include "tests/support/server_process.h"
#include "tetrefine/v1/tetrefine.grpc.pb.h"
#include "wire/conversion.h"
#include "wire/request_writer.h"

namespace tetrefine::hardening {
namespace {

using ::tetrefine::testing::FiveTetMesh;
using ::tetrefine::testing::SendRaw;
using ::tetrefine::testing::ServerProcess;
using ::tetrefine::testing::TestVolume;

struct Responses {
  grpc::Status status;
  size_t count = 0;
  size_t largest_bytes = 0;
  size_t largest_chunk_elements = 0;
};

// Sends `w` and records the size of every response message.
Responses Call(const std::shared_ptr<grpc::Channel>& channel, const Workload& w) {
  v1::Refiner::Stub stub(channel);
  grpc::ClientContext context;
  context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(60));
  auto stream = stub.Refine(&context);
  wire::WriteRequest(w.options, w.volume, w.mesh, size_t{1} << 20,
                     [&](const v1::RefineRequest& r) { return stream->Write(r); });
  stream->WritesDone();
  Responses out;
  for (v1::RefineResponse response; stream->Read(&response);) {
    ++out.count;
    out.largest_bytes = std::max(out.largest_bytes, response.ByteSizeLong());
    size_t elements = 0;
    if (response.has_vertex_chunk()) elements = response.vertex_chunk().coordinates_size() / 3;
    if (response.has_tet_chunk()) elements = response.tet_chunk().indices_size() / 4;
    if (response.has_value_chunk()) elements = response.value_chunk().values_size();
    out.largest_chunk_elements = std::max(out.largest_chunk_elements, elements);
  }
  out.status = stream->Finish();
  return out;
}

class HardeningLimitsTest : public ::testing::Test {
 protected:
  void SetUp() override {
    absl::StatusOr<std::unique_ptr<ServerProcess>> server =
        ServerProcess::Start({"--drain_seconds=2"});
    ASSERT_TRUE(server.ok()) << server.status();
    server_ = *std::move(server);
  }
  void TearDown() override {
    if (server_ != nullptr) {
      EXPECT_EQ(server_->Stop(), 0);
    }
  }
  std::unique_ptr<ServerProcess> server_;
};

// A result mesh of several MiB: 40k input tets refined once.
Workload BigResult(uint32_t response_chunk_bytes) {
  Workload w{.name = "big-result",
             .volume = TestVolume({24, 24, 24}),
             .mesh = FiveTetMesh({1.0, 1.0, 1.0}, {22.0, 22.0, 22.0}, {20, 20, 20}),
             .options = {}};
  w.options.refine.epsilon = 1e-6;
  w.options.refine.max_iterations = 1;
  w.options.refine.lattice_n = 0;
  w.options.response_chunk_bytes = response_chunk_bytes;
  return w;
}

TEST_F(HardeningLimitsTest, HugeResponseChunkHintIsClampedToThreeMiB) {
  const Responses r = Call(server_->NewChannel(), BigResult(std::numeric_limits<uint32_t>::max()));
  ASSERT_TRUE(r.status.ok()) << r.status.error_message();
  // The tets alone (16 B each, ~300k) need several chunks at the 3 MiB bound.
  EXPECT_GT(r.count, 4u);
  EXPECT_LE(r.largest_bytes, wire::kMaxChunkBytes + 64);
  EXPECT_GT(r.largest_bytes, wire::kMaxChunkBytes / 2);
}

TEST_F(HardeningLimitsTest, TinyResponseChunkHintIsRaisedTo256Bytes) {
  const Responses r = Call(server_->NewChannel(), BigResult(1));
  ASSERT_TRUE(r.status.ok()) << r.status.error_message();
  EXPECT_LE(r.largest_bytes, wire::kMinResponseChunkBytes + 64);
  EXPECT_GT(r.largest_chunk_elements, 1u) << "a 1-byte hint was taken literally";
}

TEST_F(HardeningLimitsTest, AbsurdIterationCountIsRefusedAndTheCapStaysBoundedByTheTetBudget) {
  Workload w = SmallWorkloads()[0];
  w.options.refine.epsilon = 1e-9;
  w.options.refine.max_iterations = std::numeric_limits<int32_t>::max();
  w.options.SetMaxTets(20'000);
  w.options.refine.min_edge_length = 0.0;
  const Responses refused = Call(server_->NewChannel(), w);
  EXPECT_EQ(refused.status.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED);
  EXPECT_THAT(refused.status.error_message(),
              ::testing::HasSubstr("options.max_iterations: 2147483647 exceeds this server's "
                                   "limit of 100 iterations (--max_iterations)"));
  w.options.refine.max_iterations = wire::ServiceLimits{}.max_iterations;
  const Responses r = Call(server_->NewChannel(), w);
  ASSERT_TRUE(r.status.ok()) << r.status.error_message();
  const RefineResult expected = CoreResult(w);
  EXPECT_NE(expected.stop_reason, StopReason::kMaxIterations);
  EXPECT_LE(static_cast<int64_t>(expected.mesh.tets.size()), 20'000);
}

// The request stream of `w` cut after its first message of `kind`, which `edit` changes first.
template <typename Edit>
std::vector<v1::RefineRequest> CutAfter(const Workload& w, v1::RefineRequest::KindCase kind,
                                        Edit edit) {
  std::vector<v1::RefineRequest> requests;
  wire::WriteRequest(w.options, w.volume, w.mesh, 1000, [&](const v1::RefineRequest& r) {
    requests.push_back(r);
    return true;
  });
  for (size_t i = 0; i < requests.size(); ++i) {
    if (requests[i].kind_case() == kind) {
      edit(requests[i]);
      requests.resize(i + 1);
      break;
    }
  }
  return requests;
}

TEST(HardeningMemoryLimitTest, DeclaredSizesThisProcessCannotHoldAreRefusedByName) {
#if defined(__SANITIZE_ADDRESS__)
  GTEST_SKIP() << "AddressSanitizer maps terabytes of shadow memory: no address-space limit fits";
#else
  // 1.5 GiB of address space, and limits that allow a 2 GiB volume and 4.8 GB of vertices.
  absl::StatusOr<std::unique_ptr<ServerProcess>> started = ServerProcess::Start(
      {"--drain_seconds=2", "--max_input_tets=60000000", "--threads=1"}, 0, int64_t{1536} << 20);
  ASSERT_TRUE(started.ok()) << started.status();
  std::unique_ptr<ServerProcess> server = *std::move(started);
  const Workload& w = SmallWorkloads()[0];

  const grpc::Status volume =
      SendRaw(server->NewChannel(), CutAfter(w, v1::RefineRequest::kVolumeHeader, [](auto& r) {
                v1::VolumeHeader* h = r.mutable_volume_header();
                h->mutable_dims()->set_x(1024);
                h->mutable_dims()->set_y(1024);
                h->mutable_dims()->set_z(256);
                h->clear_slab_hi();
                h->set_voxel_type(v1::VOXEL_TYPE_FLOAT64);
                h->set_total_bytes(uint64_t{8} << 28);
              }));
  EXPECT_EQ(volume.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED) << volume.error_message();
  EXPECT_THAT(volume.error_message(),
              ::testing::HasSubstr("volume_header: this server cannot allocate the 2147483648"));

  const grpc::Status mesh =
      SendRaw(server->NewChannel(), CutAfter(w, v1::RefineRequest::kMeshHeader, [](auto& r) {
                r.mutable_mesh_header()->set_vertex_count(200'000'000);
              }));
  EXPECT_EQ(mesh.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED) << mesh.error_message();
  EXPECT_THAT(mesh.error_message(),
              ::testing::HasSubstr("mesh_header: this server cannot allocate 200000000 vertices"));

  absl::StatusOr<client::ClientResult> good =
      client::RefineViaService(server->NewChannel(), w.volume, w.mesh, w.options);
  ASSERT_TRUE(good.ok()) << good.status();
  EXPECT_EQ(ResultDifference(CoreResult(w), good->result), "");
  EXPECT_EQ(server->Stop(), 0) << server->process().Output();
#endif
}

// The tet budget of a server's start-up line ("... max_output_tets N, ...").
int64_t LoggedMaxOutputTets(const std::string& log) {
  const size_t at = log.find("max_output_tets ");
  if (at == std::string::npos) return -1;
  return std::stoll(log.substr(at + 16));
}

TEST(HardeningMemoryLimitTest, AnAddressSpaceLimitSizesTheTetBudget) {
#if defined(__SANITIZE_ADDRESS__)
  GTEST_SKIP() << "AddressSanitizer maps terabytes of shadow memory: no address-space limit fits";
#else
  // Sized from physical memory, a server under `ulimit -v` offered tens of millions of tets a
  // call and ended on std::bad_alloc (outside review, 2026-11-29).
  absl::StatusOr<std::unique_ptr<ServerProcess>> started =
      ServerProcess::Start({"--drain_seconds=2", "--threads=1"}, 0, int64_t{1536} << 20);
  ASSERT_TRUE(started.ok()) << started.status();
  std::unique_ptr<ServerProcess> server = *std::move(started);
  EXPECT_THAT(server->Log(), ::testing::HasSubstr("the address space left under ulimit -v"));
  // 1.5 GiB less the idle process, less the reserve, for 4 calls at 160 bytes a tet: about 1.6 M.
  const int64_t budget = LoggedMaxOutputTets(server->Log());
  EXPECT_GT(budget, 500'000) << server->Log();
  EXPECT_LT(budget, 2'200'000) << server->Log();

  const Workload w = TinyEpsilon();
  absl::StatusOr<client::ClientResult> result =
      client::RefineViaService(server->NewChannel(), w.volume, w.mesh, w.options);
  ASSERT_TRUE(result.ok()) << result.status();
  EXPECT_EQ(result->result.stop_reason, StopReason::kTetBudget);
  EXPECT_LE(result->result.iterations.back().final_tets, budget);
  EXPECT_EQ(server->Stop(), 0) << server->process().Output();
#endif
}

TEST(HardeningMemoryLimitTest, RunningOutOfMemoryEndsTheCallNotTheServer) {
#if defined(__SANITIZE_ADDRESS__)
  GTEST_SKIP() << "AddressSanitizer maps terabytes of shadow memory: no address-space limit fits";
#else
  // A memory limit the process does not have (as a misconfigured --memory_limit_bytes would
  // claim), so that the tet budget lets a call run into the address-space limit: the call ends
  // with RESOURCE_EXHAUSTED, and the server goes on serving (until 2026-11-29 the uncaught
  // std::bad_alloc ended the process and every call in it).
  absl::StatusOr<std::unique_ptr<ServerProcess>> started =
      ServerProcess::Start({"--drain_seconds=2", "--threads=1", "--memory_limit_bytes=40000000000",
                            "--max_output_tets=50000000"},
                           0, int64_t{1024} << 20);
  ASSERT_TRUE(started.ok()) << started.status();
  std::unique_ptr<ServerProcess> server = *std::move(started);
  const Workload greedy = TinyEpsilon();
  absl::StatusOr<client::ClientResult> out_of_memory =
      client::RefineViaService(server->NewChannel(), greedy.volume, greedy.mesh, greedy.options);
  EXPECT_TRUE(absl::IsResourceExhausted(out_of_memory.status())) << out_of_memory.status();
  EXPECT_THAT(out_of_memory.status().message(),
              ::testing::HasSubstr("out of memory during the refinement, after"));

  const Workload& w = SmallWorkloads()[0];
  for (int i = 0; i < 2; ++i) {
    absl::StatusOr<client::ClientResult> good =
        client::RefineViaService(server->NewChannel(), w.volume, w.mesh, w.options);
    ASSERT_TRUE(good.ok()) << good.status();
    EXPECT_EQ(ResultDifference(CoreResult(w), good->result), "");
  }
  EXPECT_EQ(server->Stop(), 0) << server->process().Output();
#endif
}

// A client that starts calls and never reads their results kept every other client out: the
// finished calls held the memory budget until the write stall ended each a minute later (an
// outside review, 2026-11-29). One client's calls now hold at most what leaves another client's
// call with default options room.
TEST(HardeningMemoryLimitTest, AClientThatNeverReadsLeavesRoomForAnotherClientsDefaultCall) {
  const std::string tokens = (std::filesystem::temp_directory_path() /
                              ("tetrefine_noread_tokens_" + std::to_string(::getpid())))
                                 .string();
  std::ofstream(tokens) << "hog hog-token-0123456789abcdef\nother other-token-0123456789abcdef\n";
  // A budget of about 730 MB, a tet budget of 1.1 M tets a call (a worst case of about 185 MB):
  // one client's calls may hold about 530 MB together.
  absl::StatusOr<std::unique_ptr<ServerProcess>> started =
      ServerProcess::Start({"--drain_seconds=2", "--threads=1", "--memory_limit_bytes=1000000000",
                            "--max_output_tets=1100000", "--token_file=" + tokens,
                            "--queue_seconds=3", "--write_stall_seconds=60"});
  ASSERT_TRUE(started.ok()) << started.status();
  std::unique_ptr<ServerProcess> server = *std::move(started);

  // The hog: four calls of 1.08 M-tet results (173 MB each once refined), none read past its
  // first message. Two fit its share; the others may not start (until 2026-11-29 all four ran,
  // and held 690 MB).
  Workload hog = BigResultWorkload();
  hog.options.SetMaxTets(1'100'000);
  std::vector<v1::RefineRequest> requests;
  wire::WriteRequest(hog.options, hog.volume, hog.mesh, size_t{1} << 20,
                     [&](const v1::RefineRequest& r) {
                       requests.push_back(r);
                       return true;
                     });
  using Stream = grpc::ClientReaderWriter<v1::RefineRequest, v1::RefineResponse>;
  const std::shared_ptr<grpc::Channel> hog_channel = server->NewChannel();
  v1::Refiner::Stub hog_stub(hog_channel);
  std::vector<std::unique_ptr<grpc::ClientContext>> contexts;
  std::vector<std::unique_ptr<Stream>> streams;
  for (int call = 0; call < 4; ++call) {
    contexts.push_back(std::make_unique<grpc::ClientContext>());
    contexts.back()->AddMetadata("authorization", "Bearer hog-token-0123456789abcdef");
    contexts.back()->set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(120));
    streams.push_back(hog_stub.Refine(contexts.back().get()));
    for (const v1::RefineRequest& r : requests) ASSERT_TRUE(streams.back()->Write(r));
    streams.back()->WritesDone();
    // The first message (the iteration's statistics) says the refinement ran; the rest, the
    // mesh, is never read. The third and fourth wait for the share (3 s) and get no message.
    v1::RefineResponse first;
    EXPECT_EQ(streams.back()->Read(&first), call < 2) << "hog call " << call;
  }

  // Another client's call with default options (the server's tet budget, and 32 iterations, so
  // that its worst case is that budget's 185 MB) runs at once.
  Workload w = SmallWorkloads()[0];
  w.options.refine.max_iterations = 32;
  client::CallOptions other;
  other.bearer_token = "other-token-0123456789abcdef";
  absl::StatusOr<client::ClientResult> served =
      client::RefineViaService(server->NewChannel(), w.volume, w.mesh, w.options, {}, other);
  ASSERT_TRUE(served.ok()) << served.status();
  EXPECT_EQ(ResultDifference(CoreResult(w), served->result), "");

  // The hog's third and fourth calls waited for its share, then were refused by name.
  for (int call = 2; call < 4; ++call) {
    const grpc::Status refused = streams[call]->Finish();
    EXPECT_EQ(refused.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED)
        << refused.error_message();
    EXPECT_THAT(refused.error_message(),
                ::testing::HasSubstr("one client's calls may hold together"));
  }
  for (int call = 0; call < 2; ++call) {
    contexts[call]->TryCancel();
    streams[call]->Finish();
  }
  std::filesystem::remove(tokens);
  EXPECT_EQ(server->Stop(), 0) << server->process().Output();
}

}  // namespace
}  // namespace tetrefine::hardening
