#pragma once

#include <atomic>
#include <memory>

#include "grpcpp/support/server_interceptor.h"

namespace tetrefine::server {

// Bounds how many streams the whole server keeps open for the streaming methods that need no
// identity: grpc.health.v1.Health/Watch and reflection's ServerReflectionInfo. Refine calls are
// bounded per client (--max_calls_per_identity) and by the memory budget; these were bounded
// only per connection (--max_streams_per_connection), so a client spreading Watch streams over
// many connections grew the server by about 18 KB a stream without limit (found by a service
// sweep: 100 k streams over 1,000 connections, 1.85 GB). A stream over `max_streams` is
// cancelled as it arrives (the client sees CANCELLED; gRPC 1.51 gives an interceptor no other
// status to answer with); Check and every other unary call are not counted.
class SideStreamCap : public grpc::experimental::ServerInterceptorFactoryInterface {
 public:
  // max_streams >= 1.
  explicit SideStreamCap(int max_streams);

  grpc::experimental::Interceptor* CreateServerInterceptor(
      grpc::experimental::ServerRpcInfo* info) override;

 private:
  int max_streams_;
  // Shared with the interceptors, which may end after the factory (they end with their calls).
  std::shared_ptr<std::atomic<int>> open_ = std::make_shared<std::atomic<int>>(0);
};

}  // namespace tetrefine::server
