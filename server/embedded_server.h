#pragma once

#include <memory>

#include "absl/status/statusor.h"
#include "grpcpp/grpcpp.h"
#include "server/refiner_service.h"

namespace tetrefine::server {

// The tetrefine service inside this process, with no listening port: a CLI runs refinements
// through Channel() along the very code path a remote server takes.
class EmbeddedServer {
 public:
  // Starts the service with `config` (the same limits a remote server has).
  static absl::StatusOr<std::unique_ptr<EmbeddedServer>> Start(const ServiceConfig& config = {});

  // Shuts the server down; calls still running are cancelled.
  ~EmbeddedServer();
  EmbeddedServer(const EmbeddedServer&) = delete;
  EmbeddedServer& operator=(const EmbeddedServer&) = delete;

  // A new in-process channel to the server.
  std::shared_ptr<grpc::Channel> Channel(
      const grpc::ChannelArguments& args = grpc::ChannelArguments()) const;

  RefinerService& service() { return *service_; }

 private:
  EmbeddedServer() = default;

  std::unique_ptr<RefinerService> service_;
  std::unique_ptr<grpc::Server> server_;
};

}  // namespace tetrefine::server
