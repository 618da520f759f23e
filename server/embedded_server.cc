#include "server/embedded_server.h"

#include <chrono>

#include "server/server_setup.h"

namespace tetrefine::server {

absl::StatusOr<std::unique_ptr<EmbeddedServer>> EmbeddedServer::Start(const ServiceConfig& config) {
  InitGrpcFeatures();  // before the builder exists
  std::unique_ptr<EmbeddedServer> embedded(new EmbeddedServer());
  embedded->service_ = std::make_unique<RefinerService>(config);
  grpc::ServerBuilder builder;
  embedded->server_ = StartServer(config, embedded->service_.get(), &builder);
  if (embedded->server_ == nullptr) {
    return absl::InternalError("could not start the embedded tetrefine server");
  }
  return embedded;
}

EmbeddedServer::~EmbeddedServer() {
  // The service polls for cancellation, so an immediate deadline still ends calls promptly.
  server_->Shutdown(std::chrono::system_clock::now());
  server_->Wait();
}

std::shared_ptr<grpc::Channel> EmbeddedServer::Channel(const grpc::ChannelArguments& args) const {
  return server_->InProcessChannel(args);
}

}  // namespace tetrefine::server
