#pragma once

#include <memory>

#include "grpcpp/grpcpp.h"
#include "server/refiner_service.h"

namespace tetrefine::server {

// Turns on the process-wide gRPC features every tetrefine server offers: the grpc.health.v1
// service and server reflection. Idempotent; must run before a ServerBuilder is constructed
// (both hook in there).
void InitGrpcFeatures();

// Registers `service` on `builder` (which carries the caller's listening ports, if any), applies
// the message size limit, starts the server and marks it SERVING, both as a whole ("") and as
// "tetrefine.v1.Refiner". Shared by the network server, the embedded one and the tests, so all
// serve exactly the same thing. Null if the server could not start.
std::unique_ptr<grpc::Server> StartServer(const ServiceConfig& config, RefinerService* service,
                                          grpc::ServerBuilder* builder);

}  // namespace tetrefine::server
