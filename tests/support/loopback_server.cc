#include "tests/support/loopback_server.h"

#include <chrono>
#include <string>

#include "gtest/gtest.h"
#include "server/server_setup.h"
#include "tests/support/server_process.h"
#include "tetrefine/v1/tetrefine.grpc.pb.h"

namespace tetrefine::testing {

LoopbackServer::LoopbackServer(const server::ServiceConfig& config,
                               const server::ServerOptions& options) {
  server::InitGrpcFeatures();  // before the builder exists
  service_ = std::make_unique<server::RefinerService>(config);
  grpc::ServerBuilder builder;
  builder.AddListeningPort("127.0.0.1:0", grpc::InsecureServerCredentials(), &port_);
  server_ = server::StartServer(config, service_.get(), &builder, options);
  EXPECT_NE(server_, nullptr);
  EXPECT_NE(port_, 0);
}

LoopbackServer::~LoopbackServer() {
  server_->Shutdown(std::chrono::system_clock::now());
  server_->Wait();
}

std::shared_ptr<grpc::Channel> LoopbackServer::NewChannel() const {
  std::shared_ptr<grpc::Channel> channel = NewUnsharedChannel("127.0.0.1:" + std::to_string(port_));
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

}  // namespace tetrefine::testing
