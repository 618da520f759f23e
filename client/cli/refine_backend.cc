#include "client/cli/refine_backend.h"

#include <algorithm>
#include <chrono>
#include <functional>
#include <optional>
#include <utility>

#include "absl/strings/ascii.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_split.h"
#include "client/sharding/sharded_refine.h"
#include "server/embedded_server.h"
#include "server/memory_budget.h"

namespace tetrefine::cli {
namespace {

// What a list of servers takes (GetServerInfo of each).
struct ServerSizes {
  size_t chunk_bytes = 0;       // the request chunk the smallest message limit allows
  int64_t max_output_tets = 0;  // the smallest output tet limit; 0 when a server does not say
  // Per server, its max_concurrent_refinements (0: unknown, or down).
  std::vector<int> max_concurrent;
};

// The ServerSizes of the servers behind `channels`. A server without GetServerInfo
// (UNIMPLEMENTED) gets the default chunk and leaves the tet limit unknown. With `unreachable`
// set (a sharded run, whose parts move to the next server when one is down), an UNAVAILABLE
// server is passed to it and skipped, unless no server answers at all.
absl::StatusOr<ServerSizes> AskServerSizes(
    const std::vector<std::shared_ptr<grpc::Channel>>& channels, const std::string& token,
    const std::function<void(size_t index, const absl::Status& status)>& unreachable = nullptr) {
  ServerSizes sizes{.chunk_bytes = client::CallOptions{}.chunk_bytes,
                    .max_output_tets = 0,
                    .max_concurrent = std::vector<int>(channels.size(), 0)};
  bool every_limit_known = true;
  std::vector<std::pair<size_t, absl::Status>> down;
  for (size_t i = 0; i < channels.size(); ++i) {
    absl::StatusOr<client::ServerInfo> info = client::GetServerInfo(
        channels[i], std::chrono::system_clock::now() + std::chrono::seconds(30), token);
    if (unreachable && absl::IsUnavailable(info.status())) {
      down.emplace_back(i, info.status());
      continue;
    }
    if (absl::IsUnimplemented(info.status())) {
      every_limit_known = false;
      continue;
    }
    if (!info.ok()) return info.status();
    sizes.chunk_bytes =
        std::min(sizes.chunk_bytes,
                 client::ChunkBytesFor(info->limits.max_message_bytes, sizes.chunk_bytes));
    sizes.max_concurrent[i] = info->limits.max_concurrent_refinements;
    const int64_t limit = info->limits.max_output_tets;
    if (limit <= 0) every_limit_known = false;
    sizes.max_output_tets =
        sizes.max_output_tets == 0 ? limit : std::min(sizes.max_output_tets, limit);
  }
  if (!down.empty() && down.size() == channels.size()) return down.back().second;
  for (const auto& [index, status] : down) unreachable(index, status);
  if (!every_limit_known) sizes.max_output_tets = 0;
  return sizes;
}

class ChannelBackend : public RefineBackend {
 public:
  ChannelBackend(std::string name, std::shared_ptr<grpc::Channel> channel, std::string token,
                 bool ask_server)
      : name_(std::move(name)), channel_(std::move(channel)), ask_server_(ask_server) {
    call_.bearer_token = std::move(token);
  }

  std::string Name() const override { return name_; }

  absl::StatusOr<client::ClientResult> Refine(const Volume& volume, const Mesh& mesh,
                                              const client::RefineRequestOptions& options,
                                              const client::RefineCallbacks& callbacks) override {
    if (ask_server_) {
      absl::StatusOr<ServerSizes> sizes = AskServerSizes({channel_}, call_.bearer_token);
      if (!sizes.ok()) return sizes.status();
      call_.chunk_bytes = sizes->chunk_bytes;
      ask_server_ = false;
    }
    return client::RefineViaService(channel_, volume, mesh, options, callbacks, call_);
  }

 private:
  std::string name_;
  std::shared_ptr<grpc::Channel> channel_;
  bool ask_server_;
  client::CallOptions call_;
};

class EmbeddedBackend : public ChannelBackend {
 public:
  explicit EmbeddedBackend(std::unique_ptr<server::EmbeddedServer> server)
      : ChannelBackend("embedded service", server->Channel(), "", /*ask_server=*/false),
        server_(std::move(server)) {}

 private:
  std::unique_ptr<server::EmbeddedServer> server_;
};

// The mesh cut into parts refined concurrently over several servers; the merged result is the
// unsharded one (client/sharding/sharded_refine.h).
class ShardedBackend : public RefineBackend {
 public:
  ShardedBackend(std::string name, std::vector<std::string> addresses,
                 std::vector<std::shared_ptr<grpc::Channel>> channels, int shards,
                 std::string token)
      : name_(std::move(name)),
        addresses_(std::move(addresses)),
        channels_(std::move(channels)),
        shards_(shards) {
    call_.bearer_token = std::move(token);
  }

  std::string Name() const override { return name_; }

  absl::StatusOr<client::ClientResult> Refine(const Volume& volume, const Mesh& mesh,
                                              const client::RefineRequestOptions& options,
                                              const client::RefineCallbacks& callbacks) override {
    absl::StatusOr<LiveServers> live = AskServers(callbacks);
    if (!live.ok()) return live.status();
    call_.chunk_bytes = live->chunk_bytes;
    return sharding::RefineSharded(live->channels, volume, mesh,
                                   WithTheServersBudget(options, *live), shards_, callbacks, call_,
                                   live->addresses, live->max_concurrent);
  }

  absl::StatusOr<sharding::ShardedResult> RefineInPieces(
      const Volume& volume, const Mesh& mesh, const client::RefineRequestOptions& options,
      const client::RefineCallbacks& callbacks) override {
    absl::StatusOr<LiveServers> live = AskServers(callbacks);
    if (!live.ok()) return live.status();
    call_.chunk_bytes = live->chunk_bytes;
    return sharding::RefineShardedInPieces(live->channels, volume, mesh,
                                           WithTheServersBudget(options, *live), shards_, callbacks,
                                           call_, live->addresses, live->max_concurrent);
  }

 private:
  struct LiveServers {
    size_t chunk_bytes = 0;
    int64_t max_output_tets = 0;  // the smallest limit of the servers, 0 when one did not say
    std::vector<std::shared_ptr<grpc::Channel>> channels;
    std::vector<std::string> addresses;
    std::vector<int> max_concurrent;  // parallel to channels: their concurrent call limits
  };

  // Without --max-tets the run's budget is the smallest output limit of the servers that
  // answered, sent with every part. It was the smallest limit a part's server reported, so that
  // under the halo schemes, whose small iterations all go to the first address, swapping two
  // servers with different limits changed the result (an outside review: 90,051 tets, converged,
  // against 17,616 at the tet budget).
  static client::RefineRequestOptions WithTheServersBudget(client::RefineRequestOptions options,
                                                           const LiveServers& live) {
    if (!options.send_max_tets && live.max_output_tets > 0) {
      options.refine.max_tets = live.max_output_tets;
      options.send_max_tets = true;
    }
    return options;
  }

  // The servers that answer, and the chunk size every one of them takes. A replica that is down
  // does not stop the run: the operator is told once, and it is left out of this run (it was
  // tried again, and warned about, in every iteration; the mesh does not depend on which
  // servers refine it).
  absl::StatusOr<LiveServers> AskServers(const client::RefineCallbacks& callbacks) {
    std::vector<bool> down(channels_.size(), false);
    absl::StatusOr<ServerSizes> sizes =
        AskServerSizes(channels_, call_.bearer_token, [&](size_t i, const absl::Status& status) {
          down[i] = true;
          if (!callbacks.on_warning) return;
          callbacks.on_warning(absl::StrCat(addresses_[i], " is unreachable (",
                                            absl::StatusCodeToString(status.code()), ": ",
                                            status.message(), "); its parts go to the others"));
        });
    if (!sizes.ok()) return sizes.status();
    LiveServers live;
    live.chunk_bytes = sizes->chunk_bytes;
    live.max_output_tets = sizes->max_output_tets;
    for (size_t i = 0; i < channels_.size(); ++i) {
      if (down[i]) continue;
      live.channels.push_back(channels_[i]);
      live.addresses.push_back(addresses_[i]);
      live.max_concurrent.push_back(sizes->max_concurrent[i]);
    }
    return live;
  }

  std::string name_;
  std::vector<std::string> addresses_;  // parallel to channels_, for messages
  std::vector<std::shared_ptr<grpc::Channel>> channels_;
  int shards_;
  client::CallOptions call_;
};

}  // namespace

absl::StatusOr<sharding::ShardedResult> RefineBackend::RefineInPieces(
    const Volume&, const Mesh&, const client::RefineRequestOptions&,
    const client::RefineCallbacks&) {
  return absl::UnimplementedError(
      absl::StrCat(Name(), " has no parts to keep as pieces: a .pvtu needs a sharded run"));
}

absl::StatusOr<std::unique_ptr<RefineBackend>> StartEmbeddedBackend(
    const server::ServiceConfig& config) {
  absl::StatusOr<std::unique_ptr<server::EmbeddedServer>> server =
      server::EmbeddedServer::Start(config);
  if (!server.ok()) return server.status();
  return std::make_unique<EmbeddedBackend>(std::move(*server));
}

std::unique_ptr<RefineBackend> MakeRemoteBackend(std::string address,
                                                 std::shared_ptr<grpc::Channel> channel,
                                                 std::string bearer_token) {
  return std::make_unique<ChannelBackend>(absl::StrCat("server ", address), std::move(channel),
                                          std::move(bearer_token), /*ask_server=*/true);
}

absl::StatusOr<std::unique_ptr<RefineBackend>> ChooseBackend(const BackendChoice& choice) {
  if (choice.shards > 0) {
    // "a:1, b:2" as well as "a:1,b:2": the space went into the second address, which was then
    // reported unreachable and left out (an outside review).
    std::vector<std::string> addresses;
    for (absl::string_view address : absl::StrSplit(choice.server, ',')) {
      address = absl::StripAsciiWhitespace(address);
      if (!address.empty()) addresses.emplace_back(address);
    }
    std::vector<std::shared_ptr<grpc::Channel>> channels;
    for (const std::string& address : addresses) {
      absl::StatusOr<std::shared_ptr<grpc::Channel>> channel = MakeChannel(address, choice.tls);
      if (!channel.ok()) return channel.status();
      channels.push_back(*std::move(channel));
    }
    if (channels.empty()) return absl::InvalidArgumentError("--server: no address");
    return std::make_unique<ShardedBackend>(
        absl::StrCat(choice.shards, " shards over ", channels.size(), " server",
                     channels.size() == 1 ? "" : "s", " (", choice.server, ")"),
        std::move(addresses), std::move(channels), choice.shards, choice.token);
  }
  if (!choice.server.empty()) {
    absl::StatusOr<std::shared_ptr<grpc::Channel>> channel = MakeChannel(choice.server, choice.tls);
    if (!channel.ok()) return channel.status();
    return MakeRemoteBackend(choice.server, *channel, choice.token);
  }
  server::ServiceConfig config;
  config.refine_threads = choice.threads;
  wire::ServiceLimits& limits = config.limits;
  limits.max_voxels = std::max(limits.max_voxels, choice.voxels);
  // The service admits 4 vertices per admitted tet.
  limits.max_input_tets = std::max({limits.max_input_tets, choice.tets, (choice.vertices + 3) / 4});
  // Under `ulimit -v` or `-d` the tet budget is what the address space left holds, at the
  // server's bytes per output tet (a whole CLI run peaked at 133 bytes of address space per output
  // tet, 5.6 M tets, 2026-11-29): the run then stops at `tet_budget` with its last mesh written,
  // where it ended on std::bad_alloc with nothing (an outside review, 2026-11-29). A --max-tets
  // above that is the user's to ask for.
  if (std::optional<int64_t> left = server::AddressSpaceLeft()) {
    const int64_t fits = server::BudgetForLimit(*left) / server::kDefaultBytesPerOutputTet;
    limits.max_output_tets = std::clamp<int64_t>(fits, 1, limits.max_output_tets);
  }
  limits.max_output_tets = std::max(limits.max_output_tets, choice.max_tets.value_or(0));
  // The work caps too: the CLI's own flag ranges bound them, and a shared server's defaults
  // refused what the flags allowed (--lattice-n 17, --max-iterations 101) with a message naming
  // server flags the user cannot set.
  limits.max_iterations = std::max(limits.max_iterations, choice.max_iterations);
  limits.max_lattice_n = std::max(limits.max_lattice_n, choice.lattice_n);
  const int64_t sampled = choice.lattice_max_tets == 0
                              ? limits.max_output_tets
                              : std::min(choice.lattice_max_tets, limits.max_output_tets);
  limits.max_lattice_points =
      std::max(limits.max_lattice_points, wire::LatticePointsPerTet(choice.lattice_n) * sampled);
  return StartEmbeddedBackend(config);
}

}  // namespace tetrefine::cli
