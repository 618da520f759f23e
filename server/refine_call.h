#pragma once

#include <cstdint>

#include "grpcpp/grpcpp.h"
#include "server/refiner_service.h"
#include "tetrefine/v1/tetrefine.pb.h"

namespace tetrefine::server {

using RefineStream = grpc::ServerReaderWriter<v1::RefineResponse, v1::RefineRequest>;

// What a call did, for its log line.
struct CallRecord {
  int64_t bytes_in = 0;
  int64_t tets_in = 0;
  int64_t tets_out = 0;
  int iterations = 0;
};

// One Refine call from first request to last response: read and check the whole input, refine
// (stopping promptly on cancellation or deadline), stream the results.
grpc::Status RunRefineCall(const ServiceConfig& config, grpc::ServerContext* context,
                           RefineStream* stream, CallRecord* record);

}  // namespace tetrefine::server
