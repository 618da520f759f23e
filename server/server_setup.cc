#include "server/server_setup.h"

#include <algorithm>
#include <climits>
#include <mutex>
#include <string>
#include <vector>

#include "grpcpp/ext/proto_server_reflection_plugin.h"
#include "grpcpp/health_check_service_interface.h"
#include "grpcpp/impl/server_builder_option.h"
#include "grpcpp/resource_quota.h"
#include "server/side_stream_cap.h"

namespace tetrefine::server {
namespace {

int Milliseconds(double seconds) {
  return static_cast<int>(std::clamp(seconds * 1000.0, 1.0, static_cast<double>(INT_MAX)));
}

// Decides for one server whether it serves reflection. Loading grpc++_reflection registers its
// plugin for every server of the process; this option takes it out, then adds it back when wanted
// (so exactly once either way).
class ReflectionOption : public grpc::ServerBuilderOption {
 public:
  explicit ReflectionOption(bool enabled) : enabled_(enabled) {}
  void UpdateArguments(grpc::ChannelArguments* /*args*/) override {}
  void UpdatePlugins(std::vector<std::unique_ptr<grpc::ServerBuilderPlugin>>* plugins) override {
    auto reflection = std::make_unique<grpc::reflection::ProtoServerReflectionPlugin>();
    const std::string name = reflection->name();
    std::erase_if(*plugins, [&](const auto& plugin) { return plugin->name() == name; });
    if (enabled_) plugins->push_back(std::move(reflection));
  }

 private:
  bool enabled_;
};

}  // namespace

void InitGrpcFeatures() {
  static std::once_flag once;
  std::call_once(once, [] { grpc::EnableDefaultHealthCheckService(true); });
}

std::unique_ptr<grpc::Server> StartServer(const ServiceConfig& config, RefinerService* service,
                                          grpc::ServerBuilder* builder,
                                          const ServerOptions& options) {
  InitGrpcFeatures();
  builder->RegisterService(service);
  builder->SetMaxReceiveMessageSize(
      static_cast<int>(std::clamp<int64_t>(config.limits.max_message_bytes, 1, INT_MAX)));
  // Responses are chunked to at most 3 MiB; the send limit stays gRPC's default (unlimited).
  // Compressed requests are refused (UNIMPLEMENTED, from their grpc-encoding header) rather than
  // inflated: gRPC 1.51 inflates a message whole before it compares it with the size limit, so
  // a 1.5 MB gzip message of zeros took a 2 GiB server to 1.7-2.3 GiB and 9-15 s of CPU before
  // its RESOURCE_EXHAUSTED (found by a service sweep). Our clients never compress: the volume and
  // mesh chunks are binary and already dense.
  builder->SetCompressionAlgorithmSupportStatus(GRPC_COMPRESS_DEFLATE, false);
  builder->SetCompressionAlgorithmSupportStatus(GRPC_COMPRESS_GZIP, false);
  // A connection must finish its handshake (HTTP/2 preface, TLS) within this: gRPC's default
  // of 120 s let silent sockets pile up against the open-file limit (service sweep).
  builder->AddChannelArgument(GRPC_ARG_SERVER_HANDSHAKE_TIMEOUT_MS,
                              Milliseconds(options.handshake_seconds));
  builder->AddChannelArgument(GRPC_ARG_MAX_CONCURRENT_STREAMS,
                              std::max(1, options.max_streams_per_connection));
  builder->AddChannelArgument(GRPC_ARG_KEEPALIVE_TIME_MS, Milliseconds(options.keepalive_seconds));
  builder->AddChannelArgument(GRPC_ARG_KEEPALIVE_TIMEOUT_MS,
                              Milliseconds(options.keepalive_timeout_seconds));
  builder->AddChannelArgument(GRPC_ARG_KEEPALIVE_PERMIT_WITHOUT_CALLS, 1);
  builder->AddChannelArgument(GRPC_ARG_HTTP2_MIN_RECV_PING_INTERVAL_WITHOUT_DATA_MS,
                              Milliseconds(options.min_client_ping_seconds));
  builder->AddChannelArgument(GRPC_ARG_MAX_CONNECTION_IDLE_MS,
                              Milliseconds(options.max_connection_idle_seconds));
  // gRPC binds with SO_REUSEPORT by default: a second server on a port in use started, and the
  // kernel split new connections between the two (found by an operator sweep, with two servers
  // of different limits answering one address at random). A port in use is now refused.
  builder->AddChannelArgument(GRPC_ARG_ALLOW_REUSEPORT, 0);
  builder->SetOption(std::make_unique<ReflectionOption>(options.reflection));
  std::vector<std::unique_ptr<grpc::experimental::ServerInterceptorFactoryInterface>> caps;
  caps.push_back(std::make_unique<SideStreamCap>(std::max(1, options.max_side_streams)));
  builder->experimental().SetInterceptorCreators(std::move(caps));
  // gRPC's own memory (calls, streams, connection buffers) lives in the headroom left outside
  // the calls' memory budget, and had no quota. Measured 2026-11-28 (a service sweep's raw
  // HTTP/2 client): 900 connections opening 100 health Watch streams each (all but 1000
  // cancelled by SideStreamCap) peaked at 1.12 GB, 486 MB under a 256 MiB quota. It narrows such
  // bursts without bounding them (1,500 connections: 1.44 GB under the same quota): only a
  // proxy bounds the connections (docs/results/service_abuse.md).
  if (options.grpc_memory_bytes > 0) {
    grpc::ResourceQuota quota("tetrefine_server");
    quota.Resize(static_cast<size_t>(options.grpc_memory_bytes));
    builder->SetResourceQuota(quota);
  }

  std::unique_ptr<grpc::Server> server = builder->BuildAndStart();
  if (server == nullptr) return nullptr;
  if (grpc::HealthCheckServiceInterface* health = server->GetHealthCheckService()) {
    health->SetServingStatus(true);
    health->SetServingStatus(v1::Refiner::service_full_name(), true);
  }
  return server;
}

}  // namespace tetrefine::server
