#pragma once

#include <chrono>
#include <memory>
#include <string>
#include <vector>

#include "grpcpp/grpcpp.h"

namespace tetrefine::hardening {

inline constexpr char kRefineMethod[] = "/tetrefine.v1.Refiner/Refine";
inline constexpr char kServerInfoMethod[] = "/tetrefine.v1.Refiner/GetServerInfo";

// One call of `method` whose request messages are the given bytes, sent as they are (they need
// not parse as the method's request): what a broken or hostile client puts on the wire. Returns
// the call's status, and the response messages' bytes in `responses` when it is not null; the
// whole call is bounded by `timeout`.
grpc::Status SendRawBytes(const std::shared_ptr<grpc::Channel>& channel,
                          const std::vector<std::string>& messages,
                          std::chrono::milliseconds timeout = std::chrono::seconds(30),
                          const char* method = kRefineMethod,
                          std::vector<std::string>* responses = nullptr);

}  // namespace tetrefine::hardening
