#pragma once

// An in-process tetrefine server on a loopback port, and raw calls to it: for the service tests
// that need a real gRPC server but not the binary.

#include <memory>
#include <vector>

#include "grpcpp/grpcpp.h"
#include "server/refiner_service.h"
#include "server/server_setup.h"
#include "tetrefine/v1/tetrefine.pb.h"

namespace tetrefine::testing {

// A real tetrefine server on a loopback port.
class LoopbackServer {
 public:
  explicit LoopbackServer(const server::ServiceConfig& config = {},
                          const server::ServerOptions& options = {});
  ~LoopbackServer();
  std::shared_ptr<grpc::Channel> NewChannel() const;
  server::RefinerService& service() { return *service_; }
  int port() const { return port_; }

 private:
  std::unique_ptr<server::RefinerService> service_;
  std::unique_ptr<grpc::Server> server_;
  int port_ = 0;
};

// Sends `requests` as one Refine call, exactly as given, and returns the call's status.
grpc::Status SendRaw(const std::shared_ptr<grpc::Channel>& channel,
                     const std::vector<v1::RefineRequest>& requests);

}  // namespace tetrefine::testing
