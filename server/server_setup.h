#pragma once

#include <memory>

#include "grpcpp/grpcpp.h"
#include "server/refiner_service.h"

namespace tetrefine::server {

// Connection-level settings of a server (gRPC channel arguments), and its optional services.
struct ServerOptions {
  // The server pings a connection idle for this long and drops it when no answer comes within
  // keepalive_timeout_seconds: a client that vanished without closing (a pulled cable, a dead
  // NAT entry) does not keep its calls open until their own time limits.
  double keepalive_seconds = 60;
  double keepalive_timeout_seconds = 20;
  // Clients may keep their connections alive with pings this often (gRPC's default, 5 minutes,
  // makes the server close a connection whose client pings every 30 s as "too many pings").
  double min_client_ping_seconds = 10;
  // A connection with no call for this long is closed (the client reconnects when it needs to).
  double max_connection_idle_seconds = 300;
  // grpc.reflection.v1alpha.ServerReflection (what grpcurl lists and describes).
  bool reflection = true;
  // Streams one connection may have open at once (HTTP/2 SETTINGS_MAX_CONCURRENT_STREAMS; gRPC's
  // default is unlimited). A client multiplexing more waits for a stream to end. Found by a
  // service sweep: 160 k health Watch streams over 8 connections held 1.6 GB outside the memory
  // budget. Refine calls are limited further per client (--max_calls_per_identity).
  int max_streams_per_connection = 100;
  // Health Watch and reflection streams the whole server keeps open at once (SideStreamCap,
  // server/side_stream_cap.h): these need no identity, so per-client quotas do not bound them.
  // About 18 KB each.
  int max_side_streams = 1000;
  // A gRPC ResourceQuota for the server's own memory (0: none, as embedded servers run).
  int64_t grpc_memory_bytes = 0;
  // A new connection has this long to complete its handshake (HTTP/2 preface, and TLS) before
  // it is closed.
  double handshake_seconds = 20;
};

// Turns on the process-wide gRPC features every tetrefine server offers: the grpc.health.v1
// service. Idempotent; must run before a ServerBuilder is constructed.
void InitGrpcFeatures();

// Registers `service` on `builder` (which carries the caller's listening ports, if any), applies
// the message size limit and `options`, starts the server and marks it SERVING, both as a whole
// ("") and as "tetrefine.v1.Refiner". Shared by the network server, the embedded one and the
// tests, so all serve exactly the same thing. Null if the server could not start.
std::unique_ptr<grpc::Server> StartServer(const ServiceConfig& config, RefinerService* service,
                                          grpc::ServerBuilder* builder,
                                          const ServerOptions& options = {});

}  // namespace tetrefine::server
