#include "server/server_setup.h"

#include <algorithm>
#include <climits>
#include <mutex>

#include "grpcpp/ext/proto_server_reflection_plugin.h"
#include "grpcpp/health_check_service_interface.h"

namespace tetrefine::server {

void InitGrpcFeatures() {
  static std::once_flag once;
  std::call_once(once, [] {
    grpc::EnableDefaultHealthCheckService(true);
    grpc::reflection::InitProtoReflectionServerBuilderPlugin();
  });
}

std::unique_ptr<grpc::Server> StartServer(const ServiceConfig& config, RefinerService* service,
                                          grpc::ServerBuilder* builder) {
  InitGrpcFeatures();
  builder->RegisterService(service);
  builder->SetMaxReceiveMessageSize(
      static_cast<int>(std::clamp<int64_t>(config.limits.max_message_bytes, 1, INT_MAX)));
  // Responses are chunked to at most 3 MiB; the send limit stays gRPC's default (unlimited).
  std::unique_ptr<grpc::Server> server = builder->BuildAndStart();
  if (server == nullptr) return nullptr;
  if (grpc::HealthCheckServiceInterface* health = server->GetHealthCheckService()) {
    health->SetServingStatus(true);
    health->SetServingStatus(v1::Refiner::service_full_name(), true);
  }
  return server;
}

}  // namespace tetrefine::server
