#include "server/side_stream_cap.h"

#include <string_view>
#include <utility>

#include "grpcpp/server_context.h"

namespace tetrefine::server {
namespace {

// One call's share of the count: taken when the call arrives, given back when it ends (gRPC
// destroys a call's interceptors with the call).
class CountedStream : public grpc::experimental::Interceptor {
 public:
  CountedStream(grpc::experimental::ServerRpcInfo* info, std::shared_ptr<std::atomic<int>> open,
                int max_streams)
      : info_(info), open_(std::move(open)), over_(open_->fetch_add(1) >= max_streams) {}
  ~CountedStream() override { open_->fetch_sub(1); }

  void Intercept(grpc::experimental::InterceptorBatchMethods* methods) override {
    if (over_ && methods->QueryInterceptionHookPoint(
                     grpc::experimental::InterceptionHookPoints::POST_RECV_INITIAL_METADATA)) {
      info_->server_context()->TryCancel();
    }
    methods->Proceed();
  }

 private:
  grpc::experimental::ServerRpcInfo* info_;
  std::shared_ptr<std::atomic<int>> open_;
  bool over_;
};

// Whether `method` (a full gRPC method name, "/package.Service/Method") is one SideStreamCap
// counts.
bool IsCappedSideStream(const char* method) {
  const std::string_view m = method == nullptr ? std::string_view() : std::string_view(method);
  return m == "/grpc.health.v1.Health/Watch" ||
         m == "/grpc.reflection.v1alpha.ServerReflection/ServerReflectionInfo" ||
         m == "/grpc.reflection.v1.ServerReflection/ServerReflectionInfo";
}

}  // namespace

SideStreamCap::SideStreamCap(int max_streams) : max_streams_(max_streams) {}

grpc::experimental::Interceptor* SideStreamCap::CreateServerInterceptor(
    grpc::experimental::ServerRpcInfo* info) {
  if (!IsCappedSideStream(info->method())) return nullptr;
  return new CountedStream(info, open_, max_streams_);
}

}  // namespace tetrefine::server
