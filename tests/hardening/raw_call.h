#pragma once

#include <chrono>
#include <memory>
#include <string>
#include <vector>

#include "grpcpp/grpcpp.h"

namespace tetrefine::hardening {

// One Refine call whose request messages are the given bytes, sent as they are (they need not
// parse as RefineRequest): what a broken or hostile client puts on the wire. Returns the call's
// status; the whole call is bounded by `timeout`.
grpc::Status SendRawBytes(const std::shared_ptr<grpc::Channel>& channel,
                          const std::vector<std::string>& messages,
                          std::chrono::milliseconds timeout = std::chrono::seconds(30));

}  // namespace tetrefine::hardening
