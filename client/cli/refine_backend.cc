#include "client/cli/refine_backend.h"

#include <algorithm>
#include <utility>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_split.h"
#include "client/sharding/sharded_refine.h"
#include "server/embedded_server.h"

namespace tetrefine::cli {
namespace {

class ChannelBackend : public RefineBackend {
 public:
  ChannelBackend(std::string name, std::shared_ptr<grpc::Channel> channel)
      : name_(std::move(name)), channel_(std::move(channel)) {}

  std::string Name() const override { return name_; }

  absl::StatusOr<client::ClientResult> Refine(const Volume& volume, const Mesh& mesh,
                                              const client::RefineRequestOptions& options,
                                              const client::RefineCallbacks& callbacks) override {
    return client::RefineViaService(channel_, volume, mesh, options, callbacks);
  }

 private:
  std::string name_;
  std::shared_ptr<grpc::Channel> channel_;
};

class EmbeddedBackend : public ChannelBackend {
 public:
  explicit EmbeddedBackend(std::unique_ptr<server::EmbeddedServer> server)
      : ChannelBackend("embedded service", server->Channel()), server_(std::move(server)) {}

 private:
  std::unique_ptr<server::EmbeddedServer> server_;
};

// The mesh cut into parts refined concurrently over several servers; the merged result is the
// unsharded one (client/sharding/sharded_refine.h).
class ShardedBackend : public RefineBackend {
 public:
  ShardedBackend(std::string name, std::vector<std::shared_ptr<grpc::Channel>> channels, int shards)
      : name_(std::move(name)), channels_(std::move(channels)), shards_(shards) {}

  std::string Name() const override { return name_; }

  absl::StatusOr<client::ClientResult> Refine(const Volume& volume, const Mesh& mesh,
                                              const client::RefineRequestOptions& options,
                                              const client::RefineCallbacks& callbacks) override {
    return sharding::RefineSharded(channels_, volume, mesh, options, shards_, callbacks);
  }

 private:
  std::string name_;
  std::vector<std::shared_ptr<grpc::Channel>> channels_;
  int shards_;
};

}  // namespace

absl::StatusOr<std::unique_ptr<RefineBackend>> StartEmbeddedBackend(
    const server::ServiceConfig& config) {
  absl::StatusOr<std::unique_ptr<server::EmbeddedServer>> server =
      server::EmbeddedServer::Start(config);
  if (!server.ok()) return server.status();
  return std::make_unique<EmbeddedBackend>(std::move(*server));
}

std::unique_ptr<RefineBackend> MakeRemoteBackend(std::string address,
                                                 std::shared_ptr<grpc::Channel> channel) {
  return std::make_unique<ChannelBackend>(absl::StrCat("server ", address), std::move(channel));
}

absl::StatusOr<std::unique_ptr<RefineBackend>> ChooseBackend(const BackendChoice& choice) {
  if (choice.shards > 0) {
    std::vector<std::shared_ptr<grpc::Channel>> channels;
    for (absl::string_view address : absl::StrSplit(choice.server, ',', absl::SkipEmpty())) {
      absl::StatusOr<std::shared_ptr<grpc::Channel>> channel =
          MakeChannel(std::string(address), choice.tls);
      if (!channel.ok()) return channel.status();
      channels.push_back(*std::move(channel));
    }
    if (channels.empty()) return absl::InvalidArgumentError("--server: no address");
    return std::make_unique<ShardedBackend>(
        absl::StrCat(choice.shards, " shards over ", channels.size(), " server",
                     channels.size() == 1 ? "" : "s", " (", choice.server, ")"),
        std::move(channels), choice.shards);
  }
  if (!choice.server.empty()) {
    absl::StatusOr<std::shared_ptr<grpc::Channel>> channel = MakeChannel(choice.server, choice.tls);
    if (!channel.ok()) return channel.status();
    return MakeRemoteBackend(choice.server, *channel);
  }
  server::ServiceConfig config;
  config.refine_threads = choice.threads;
  wire::ServiceLimits& limits = config.limits;
  limits.max_voxels = std::max(limits.max_voxels, choice.voxels);
  // The service admits 4 vertices per admitted tet.
  limits.max_input_tets = std::max({limits.max_input_tets, choice.tets, (choice.vertices + 3) / 4});
  limits.max_output_tets = std::max(limits.max_output_tets, choice.max_tets.value_or(0));
  return StartEmbeddedBackend(config);
}

}  // namespace tetrefine::cli
