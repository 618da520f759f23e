// Server limits answer RESOURCE_EXHAUSTED, checked on declared sizes before any allocation.

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <chrono>
#include <thread>
#include <vector>

#include "client/refine_client.h"
#include "gmock/gmock.h"
#include "grpc/health/v1/health.grpc.pb.h"
#include "gtest/gtest.h"
#include "tests/support/geometry.h"
#include "tests/support/loopback_server.h"
#include "tetrefine/v1/tetrefine.grpc.pb.h"
#include "wire/request_writer.h"

namespace tetrefine::testing {
namespace {

using ::testing::HasSubstr;
using Requests = std::vector<v1::RefineRequest>;

server::ServiceConfig SmallLimits() {
  server::ServiceConfig config;
  config.limits.max_voxels = 2000;
  config.limits.max_input_tets = 100;
  config.limits.max_output_tets = 5000;
  config.limits.max_concurrent_refinements = 1;
  config.limits.max_message_bytes = 4096;
  return config;
}

Requests GoodRequests(size_t chunk_bytes = 1000) {
  const Volume volume = TestVolume({10, 10, 10});
  const Mesh mesh = FiveTetMesh({1.0, 1.0, 1.0}, {8.0, 8.0, 8.0}, {2, 2, 2});
  RefineOptions options;
  options.epsilon = 0.05;
  options.max_iterations = 2;
  wire::RequestOptions request = wire::RequestOptionsFromCore(options);
  request.send_max_tets = false;
  Requests requests;
  wire::WriteRequest(request, volume, mesh, chunk_bytes, [&](const v1::RefineRequest& r) {
    requests.push_back(r);
    return true;
  });
  return requests;
}

// The request stream cut right after its n-th message, which `edit` changes first: what
// follows a header would never be read.
template <typename Edit>
Requests CutAfter(v1::RefineRequest::KindCase kind, Edit edit) {
  Requests requests = GoodRequests();
  for (size_t i = 0; i < requests.size(); ++i) {
    if (requests[i].kind_case() == kind) {
      edit(requests[i]);
      requests.resize(i + 1);
      return requests;
    }
  }
  ADD_FAILURE() << "no message of kind " << kind;
  return requests;
}

class ServiceLimitsTest : public ::testing::Test {
 protected:
  void ExpectExhausted(const Requests& requests, const std::vector<std::string>& parts) {
    const auto start = std::chrono::steady_clock::now();
    const grpc::Status status = SendRaw(server_.NewChannel(), requests);
    EXPECT_EQ(status.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED) << status.error_message();
    for (const std::string& part : parts) EXPECT_THAT(status.error_message(), HasSubstr(part));
    // Nothing the size of the declared counts was allocated, or this would take long (or abort).
    EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::seconds(5));
    EXPECT_TRUE(SendRaw(server_.NewChannel(), GoodRequests()).ok());
  }

  LoopbackServer server_{SmallLimits()};
};

TEST_F(ServiceLimitsTest, VolumeAboveMaxVoxels) {
  ExpectExhausted(CutAfter(v1::RefineRequest::kVolumeHeader,
                           [](v1::RefineRequest& r) {
                             r.mutable_volume_header()->mutable_dims()->set_x(30);
                             r.mutable_volume_header()->mutable_slab_hi()->set_x(30);
                           }),
                  {"volume_header", "limit of 2000 voxels (--max_voxels)"});
}

TEST_F(ServiceLimitsTest, HugeDeclaredVolume) {
  ExpectExhausted(CutAfter(v1::RefineRequest::kVolumeHeader,
                           [](v1::RefineRequest& r) {
                             v1::VolumeHeader* h = r.mutable_volume_header();
                             // The largest grid the core takes: 2^60 voxels.
                             h->mutable_dims()->set_x(int64_t{1} << 20);
                             h->mutable_dims()->set_y(int64_t{1} << 20);
                             h->mutable_dims()->set_z(int64_t{1} << 20);
                             h->clear_slab_lo();
                             h->clear_slab_hi();
                             h->set_total_bytes(~uint64_t{0});
                           }),
                  {"volume_header", "voxels"});
}

TEST_F(ServiceLimitsTest, MeshAboveMaxInputTets) {
  ExpectExhausted(CutAfter(v1::RefineRequest::kMeshHeader,
                           [](v1::RefineRequest& r) {
                             r.mutable_mesh_header()->set_tet_count(int64_t{1} << 40);
                           }),
                  {"mesh_header.tet_count", "limit of 100 input tets (--max_input_tets)"});
}

TEST_F(ServiceLimitsTest, MeshAboveMaxInputVertices) {
  ExpectExhausted(
      CutAfter(v1::RefineRequest::kMeshHeader,
               [](v1::RefineRequest& r) {
                 r.mutable_mesh_header()->set_vertex_count(int64_t{1} << 50);
               }),
      {"mesh_header.vertex_count", "limit of 400 input vertices (4 x --max_input_tets)"});
}

TEST_F(ServiceLimitsTest, MaxTetsAboveMaxOutputTets) {
  Requests requests = GoodRequests();
  requests[0].mutable_options()->set_max_tets(5001);
  ExpectExhausted(requests,
                  {"options.max_tets: 5001", "limit of 5000 output tets (--max_output_tets)"});
}

TEST_F(ServiceLimitsTest, MessageAboveMaxMessageBytes) {
  ExpectExhausted(GoodRequests(/*chunk_bytes=*/8000), {});
}

// Found by a service sweep: gRPC 1.51 inflates a compressed message whole before it compares
// it with the size limit, so 1.5 MB of gzip took a 2 GiB server past its memory. Compressed
// requests are refused from their header, before any inflating: a message that would inflate
// to 64 MiB (against a 4 KiB limit) gets UNIMPLEMENTED, and good calls go on.
TEST_F(ServiceLimitsTest, CompressedRequestsAreRefusedNotInflated) {
  for (const grpc_compression_algorithm algorithm : {GRPC_COMPRESS_GZIP, GRPC_COMPRESS_DEFLATE}) {
    SCOPED_TRACE(algorithm);
    v1::Refiner::Stub stub(server_.NewChannel());
    grpc::ClientContext context;
    context.set_compression_algorithm(algorithm);
    context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(30));
    auto stream = stub.Refine(&context);
    v1::RefineRequest bomb;
    bomb.mutable_volume_chunk()->set_data(std::string(size_t{64} << 20, '\0'));
    const auto start = std::chrono::steady_clock::now();
    stream->Write(bomb);
    stream->WritesDone();
    v1::RefineResponse response;
    while (stream->Read(&response)) {
    }
    const grpc::Status status = stream->Finish();
    EXPECT_EQ(status.error_code(), grpc::StatusCode::UNIMPLEMENTED) << status.error_message();
    EXPECT_THAT(status.error_message(), HasSubstr("is disabled"));
    EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::seconds(20));
  }
  EXPECT_TRUE(SendRaw(server_.NewChannel(), GoodRequests()).ok());
}

// Found by a service sweep: 160 k health Watch streams over 8 connections held 1.6 GB outside
// the memory budget. A connection may have max_streams_per_connection streams open; a client's
// next one waits until one ends.
TEST(ServiceConnectionLimits, StreamsPerConnectionAreCapped) {
  server::ServerOptions options;
  options.max_streams_per_connection = 2;
  LoopbackServer server({}, options);
  const std::shared_ptr<grpc::Channel> channel = server.NewChannel();
  v1::Refiner::Stub refiner(channel);
  grpc::health::v1::Health::Stub health(channel);
  const auto check = [&](double seconds) {
    grpc::ClientContext context;
    context.set_deadline(std::chrono::system_clock::now() +
                         std::chrono::milliseconds(static_cast<int>(seconds * 1000)));
    grpc::health::v1::HealthCheckResponse response;
    return health.Check(&context, {}, &response).error_code();
  };
  ASSERT_EQ(check(30), grpc::StatusCode::OK);
  // Two Refine calls that have sent their options and wait for more hold both streams.
  const Requests requests = GoodRequests();
  grpc::ClientContext first, second;
  auto a = refiner.Refine(&first);
  auto b = refiner.Refine(&second);
  ASSERT_TRUE(a->Write(requests[0]));
  ASSERT_TRUE(b->Write(requests[0]));
  // A third stream on the connection waits: no answer within its second.
  EXPECT_EQ(check(1), grpc::StatusCode::DEADLINE_EXCEEDED);
  // Once one ends, the next is served.
  first.TryCancel();
  a->Finish();
  EXPECT_EQ(check(30), grpc::StatusCode::OK);
  second.TryCancel();
  b->Finish();
}

// Found by a service sweep: Watch streams spread over many connections (100 each) grew the
// server by about 18 KB a stream without limit (1.85 GB at 100 k), since health needs no token.
// The whole server keeps at most max_side_streams open; one more is cancelled as it arrives,
// and a freed place is taken again.
TEST(ServiceConnectionLimits, WatchStreamsAreCappedAcrossConnections) {
  server::ServerOptions options;
  options.max_side_streams = 2;
  LoopbackServer server({}, options);
  struct Watch {
    std::shared_ptr<grpc::Channel> channel;
    std::unique_ptr<grpc::health::v1::Health::Stub> stub;
    grpc::ClientContext context;
    std::unique_ptr<grpc::ClientReader<grpc::health::v1::HealthCheckResponse>> reader;
  };
  // Each on its own connection: the per-connection limit is not what stops them.
  const auto open = [&] {
    auto w = std::make_unique<Watch>();
    w->channel = server.NewChannel();
    w->stub = grpc::health::v1::Health::NewStub(w->channel);
    w->context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(30));
    w->reader = w->stub->Watch(&w->context, {});
    return w;
  };
  const auto serving = [](Watch& w) {
    grpc::health::v1::HealthCheckResponse response;
    return w.reader->Read(&response) &&
           response.status() == grpc::health::v1::HealthCheckResponse::SERVING;
  };
  std::unique_ptr<Watch> first = open(), second = open();
  ASSERT_TRUE(serving(*first));
  ASSERT_TRUE(serving(*second));
  std::unique_ptr<Watch> third = open();
  EXPECT_FALSE(serving(*third));
  EXPECT_EQ(third->reader->Finish().error_code(), grpc::StatusCode::CANCELLED);
  // Check is unary and not counted.
  {
    grpc::ClientContext context;
    grpc::health::v1::HealthCheckResponse response;
    EXPECT_TRUE(first->stub->Check(&context, {}, &response).ok());
  }
  first->context.TryCancel();
  first->reader->Finish();
  // The server counts a stream until its call is torn down, a moment after the client's end.
  bool served = false;
  for (int attempt = 0; attempt < 100 && !served; ++attempt) {
    std::unique_ptr<Watch> next = open();
    served = serving(*next);
    if (!served) {
      next->reader->Finish();
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    } else {
      next->context.TryCancel();
      next->reader->Finish();
    }
  }
  EXPECT_TRUE(served);
  second->context.TryCancel();
  second->reader->Finish();
}

// A connection that never completes its HTTP/2 handshake is closed after handshake_seconds
// (gRPC's default of 120 s let silent sockets pile up against the open-file limit).
TEST(ServiceConnectionLimits, SilentConnectionsAreClosed) {
  server::ServerOptions options;
  options.handshake_seconds = 0.5;
  LoopbackServer server({}, options);
  const int fd = socket(AF_INET, SOCK_STREAM, 0);
  ASSERT_GE(fd, 0);
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_port = htons(static_cast<uint16_t>(server.port()));
  address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  ASSERT_EQ(connect(fd, reinterpret_cast<sockaddr*>(&address), sizeof(address)), 0);
  timeval wait{.tv_sec = 30, .tv_usec = 0};
  setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &wait, sizeof(wait));
  const auto start = std::chrono::steady_clock::now();
  // The server sends its own preface (SETTINGS), then closes the connection (0: end of stream)
  // long before the 30 s a read would wait.
  char bytes[256];
  ssize_t got;
  while ((got = recv(fd, bytes, sizeof(bytes), 0)) > 0) {
  }
  EXPECT_EQ(got, 0);
  EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::seconds(20));
  close(fd);
}

TEST_F(ServiceLimitsTest, AStreamStillSendingItsInputHoldsNoRefinementSlot) {
  // The only slot is free while a call has sent its options and waits for more: a slot is taken
  // when the input is complete, not when a stream opens.
  v1::Refiner::Stub stub(server_.NewChannel());
  grpc::ClientContext holder;
  auto stream = stub.Refine(&holder);
  ASSERT_TRUE(stream->Write(GoodRequests()[0]));
  for (int i = 0; i < 500 && server_.service().open_calls() == 0; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  ASSERT_EQ(server_.service().open_calls(), 1);
  EXPECT_EQ(server_.service().running_refinements(), 0);

  const grpc::Status served = SendRaw(server_.NewChannel(), GoodRequests());
  EXPECT_TRUE(served.ok()) << served.error_message();

  holder.TryCancel();
  EXPECT_EQ(stream->Finish().error_code(), grpc::StatusCode::CANCELLED);
  for (int i = 0; i < 500 && server_.service().open_calls() != 0; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  EXPECT_EQ(server_.service().open_calls(), 0);
}

}  // namespace
}  // namespace tetrefine::testing
