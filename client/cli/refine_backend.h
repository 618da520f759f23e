#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <string>

#include "absl/status/statusor.h"
#include "client/cli/grpc_channel.h"
#include "client/refine_client.h"
#include "client/sharding/sharded_refine.h"
#include "core/mesh.h"
#include "core/volume.h"
#include "grpcpp/channel.h"
#include "server/refiner_service.h"

namespace tetrefine::cli {

// Where `tetrefine refine` sends its work: the embedded service, one server, or the mesh sharded
// over several servers (--shards, client/sharding). The refine command talks only to this
// interface, so another way of running a refinement slots in as one more implementation without
// touching the command.
class RefineBackend {
 public:
  virtual ~RefineBackend() = default;

  // For messages: "embedded service" or "server host:port".
  virtual std::string Name() const = 0;

  // Refines `mesh` in the whole `volume`; the result is what core Refine returns, plus the
  // service's summary. Errors are the service's status (INVALID_ARGUMENT for bad input, ...).
  virtual absl::StatusOr<client::ClientResult> Refine(const Volume& volume, const Mesh& mesh,
                                                      const client::RefineRequestOptions& options,
                                                      const client::RefineCallbacks& callbacks) = 0;

  // The same refinement with the result kept as the parts' own meshes (ShardOptions::keep_pieces:
  // reply.result has no mesh, `pieces` hold it), so that a .pvtu is written piece by piece and
  // the result is never merged here. Only a sharded backend has parts: the others return
  // UNIMPLEMENTED.
  virtual absl::StatusOr<sharding::ShardedResult> RefineInPieces(
      const Volume& volume, const Mesh& mesh, const client::RefineRequestOptions& options,
      const client::RefineCallbacks& callbacks);
};

// The service started inside this process (server::EmbeddedServer), called through the same
// client code as a remote server. `config` sets its limits and worker threads.
absl::StatusOr<std::unique_ptr<RefineBackend>> StartEmbeddedBackend(
    const server::ServiceConfig& config);

// A tetrefine_server reached through `channel`; `address` is only for messages. Before its
// first refinement it asks the server (GetServerInfo) for its largest request message and
// chunks the input to fit. `bearer_token`: for a server with --token_file.
std::unique_ptr<RefineBackend> MakeRemoteBackend(std::string address,
                                                 std::shared_ptr<grpc::Channel> channel,
                                                 std::string bearer_token = "");

// What `tetrefine refine`'s flags say about where to run, plus the job's size.
struct BackendChoice {
  std::string server;  // --server; empty: the embedded service. Comma-separated with shards.
  int shards = 0;      // --shards; > 0: the mesh in that many parts over the --server list
  TlsFiles tls;        // --tls-*, with --server only
  std::string token;   // --token-file's token, with --server only
  int threads = 0;     // --threads, embedded only
  // The job, so that the embedded service's limits admit it.
  int64_t voxels = 0;
  int64_t vertices = 0;
  int64_t tets = 0;
  std::optional<int64_t> max_tets;
  int max_iterations = 0;
  int lattice_n = 0;
  int64_t lattice_max_tets = 0;  // 0: every tet
};

// The one place the refine command's backend is decided: with shards, the mesh cut into that
// many parts sent to the comma-separated servers (client/sharding); a remote server when
// `server` is set; else the embedded service with limits raised to fit the job (it is the user's
// own process). Errors: an unreadable TLS file (INVALID_ARGUMENT or NOT_FOUND naming it), or the
// embedded service failing to start.
absl::StatusOr<std::unique_ptr<RefineBackend>> ChooseBackend(const BackendChoice& choice);

}  // namespace tetrefine::cli
