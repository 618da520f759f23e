#pragma once

// Sharded refinement: one mesh refined as K parts on several tetrefine servers at once.
//
// Under the paper's scheme every part is refined to the end in one call. The longest-edge scheme
// and certify read the tets around an edge, so their parts go one iteration at a time, each with
// a halo of neighbouring tets (sharding/halo_parts.h), and the merged mesh is cut again for the
// next iteration: more calls, the same result.
//
// Every decision of the method is local to an edge or a face, so a mesh can be cut into parts
// that are refined independently and put back together into exactly the mesh the unsharded
// refinement gives (same vertex positions and values to the bit, same tets). Each part travels
// with only the volume slab covering it, with norm_coeff fixed to the whole volume's range.

#include <chrono>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "client/refine_client.h"
#include "core/mesh.h"
#include "core/refine.h"
#include "core/volume.h"
#include "grpcpp/channel.h"
#include "grpcpp/security/credentials.h"
#include "sharding/halo_parts.h"
#include "sharding/part_merge.h"

namespace tetrefine::sharding {

struct ShardOptions {
  int shards = 1;  // parts the mesh is cut into (at most one per tet)
  // Tries per part, each on the next target: a part whose call fails with UNAVAILABLE,
  // RESOURCE_EXHAUSTED or ABORTED (a replica gone or busy) moves on. 0: max(3, 2 * targets).
  int max_attempts = 0;
  std::chrono::milliseconds retry_backoff{100};  // before try n + 1: n times this, at most 2 s
  // Per call: chunk size and wait_for_ready; the deadline bounds the whole sharded run.
  client::CallOptions call;
  // Schemes that read neighbouring tets (longest-edge, certify): rings of tets sent around each
  // part's own tets. The default is what the scheme reads (sharding/halo_parts.h); a narrower
  // halo gives a different mesh, and exists for the test that shows it.
  int halo_rings = kHaloRings;
  // Halo schemes: an iteration is cut into fewer parts than `shards` (1, 2, 4, ...) when that
  // gives no server more than 10% more tets than `shards` parts would (HaloPartsFor in
  // sharded_refine.cc). On a
  // mesh small for `shards`, every halo holds most of the mesh, and K parts were K times the
  // work of one for the same wall time. The result is the same either way; false always cuts
  // `shards` parts (for tests of the halo merge).
  bool fewer_parts_when_halos_overlap = true;
  // The result as the parts' own meshes (ShardedResult::pieces) instead of one merged mesh: a
  // .pvtu is written from them without the whole mesh ever being put together here. Under the
  // paper's scheme no merge happens at all; the halo schemes hold the whole mesh between their
  // rounds anyway, and the pieces are then the measuring round's parts.
  bool keep_pieces = false;
  // The targets' names for messages ("server host:port"); empty: "server 2 of 3".
  std::vector<std::string> target_names;
  // Per target (parallel to the targets), the most calls to have open on it at once: its
  // max_concurrent_refinements (GetServerInfo), so that parts wait here rather than in its
  // queue, where they timed out and failed the run on a server with --max_concurrent 1 (an
  // outside review). 0 or missing: 8 (the most ever opened on one target).
  std::vector<int> max_open_calls;
};

struct ShardCallbacks {
  // A part finished an iteration on targets[target]. Calls are serialized (never two at once)
  // but come from the parts' threads. A part that is retried reports its iterations again.
  std::function<void(int part, int target, const IterationStats& stats)> on_part_iteration;
  // A part's call on targets[target] failed with a retryable `status`; it goes to next_target.
  std::function<void(int part, int target, const absl::Status& status, int next_target)> on_retry;
  // The whole mesh's statistics of an iteration, on the calling thread: under the halo schemes
  // as soon as the iteration is merged; under the paper's scheme, whose parts run every
  // iteration in one call, once all parts are done.
  std::function<void(const IterationStats& stats)> on_iteration;
  // Polled from several threads at once (it must be thread-safe); true cancels every call and
  // the run returns CANCELLED.
  std::function<bool()> should_cancel;
};

// What happened to one part.
struct ShardReport {
  int part = 0;
  int64_t input_tets = 0;
  int64_t input_vertices = 0;
  Index3 slab_lo{0, 0, 0};  // the volume samples sent: [slab_lo, slab_hi)
  Index3 slab_hi{0, 0, 0};
  int64_t volume_bytes = 0;  // voxel bytes of that slab
  int target = 0;            // where its final result came from
  int attempts = 0;          // calls made, over both rounds
  int rounds = 1;            // 2 when it had to be refined again to stop with the whole
  int iterations = 0;
  StopReason stop_reason = StopReason::kConverged;
  int64_t output_tets = 0;
  double server_seconds = 0.0;  // the final call, as the server timed it
};

struct ShardedResult {
  // As one unsharded call would return it: the merged mesh with per-tet iteration and quality;
  // per-iteration statistics combined (see result_combine.h for how, and where they differ
  // from an unsharded run's); the stop reason the unsharded run has; norm_coeff as sent.
  // service.max_tets is the budget applied, input_seconds the slowest part's input, and
  // total_seconds the wall time of the whole sharded run. With ShardOptions::keep_pieces the
  // mesh and its per-tet arrays (tet_iteration, tet_quality, tet_parent) are empty and `pieces`
  // hold them; everything else is as without.
  client::ClientResult reply;
  // With keep_pieces: one per part, in part order, each with its own vertex numbering (a vertex
  // on the boundary between two pieces is in both, with the same coordinates and value to the
  // bit). Together they hold exactly the merged result's tets, with tet_parent indexing the
  // input's tets; input vertices used by no tet are in none.
  std::vector<RefinedMesh> pieces;
  std::vector<ShardReport> shards;
  // Halo schemes: the parts each iteration was cut into (fewer than ShardOptions::shards where
  // the halos overlapped); empty under the paper's scheme, whose parts run every iteration.
  std::vector<int> parts_per_iteration;
  double split_seconds = 0.0;  // cutting the mesh into parts (here, before any call)
  double merge_seconds = 0.0;  // merging the parts' meshes and statistics
};

// Refines `mesh` in `volume` (a whole volume, or a slab holding the mesh) as `options.shards`
// parts sent concurrently to `targets`, part k first to targets[k % targets.size()].
//
// The mesh is cut by recursive coordinate bisection of tet centroids (deterministic); each part
// has its own vertex numbering and is sent with the slab covering its bounding box plus one
// voxel. norm_coeff is options.norm_coeff if set, else the range of `volume` (a slab's own range
// would change the decisions). Parts that refine further than the whole run would stop (a tet
// budget summed over the parts, or another part's quality floor) are refined a second time with
// fewer iterations, so the result is the unsharded one also then.
//
// Schemes that read neighbouring tets (longest-edge, certify) run one round per iteration: the
// current mesh cut again, each part sent with shard_options.halo_rings rings of tets around its
// own and refined one iteration (with track_parents), the children of owned tets merged; the tet
// budget and the quality floor are judged here on the merged iteration, as the core judges them.
// A last round of parts without halos and without iterations measures the result. Per-iteration
// counts (NTwE, edges, split edges, configurations, SP) are then the whole mesh's, quality and
// max error exact; mean_error, short_edges_kept, closure_edges, guard_edges, failing_tets and
// other_tilings are over the parts' tets and edges, halos included.
//
// Errors: INVALID_ARGUMENT for bad input (checked here for what splitting needs, by the servers
// for the rest, prefixed with "part k: " and naming the part's own indices); a part's
// non-retryable error, or its last retryable one, cancels the other parts and is returned,
// prefixed; CANCELLED after should_cancel. Input vertices used by no tet are kept (with their
// sampled values); face-adjacency across part boundaries is not validated.
// options.stream_every_iteration and skip_final_mesh are ignored: the parts' final meshes are
// the result.
absl::StatusOr<ShardedResult> ShardedRefine(
    const std::vector<std::shared_ptr<grpc::Channel>>& targets, const Volume& volume,
    const Mesh& mesh, const client::RefineRequestOptions& options,
    const ShardOptions& shard_options = {}, const ShardCallbacks& callbacks = {});

// The same call shape as client::RefineViaService, for code built around it (the CLI's
// RefineBackend): `shards` parts over `targets`, default ShardOptions with `call` as every
// part's call options (chunk size, bearer token). callbacks.should_cancel cancels;
// callbacks.on_iteration receives the whole mesh's statistics of each iteration as
// ShardCallbacks::on_iteration does (the parts' own iterations are not forwarded);
// callbacks.on_warning is told of each part retried on another server, naming both by
// `target_names` (parallel to `targets`; "server k" when empty); on_mesh is UNIMPLEMENTED.
// `max_open_calls`: ShardOptions::max_open_calls.
absl::StatusOr<client::ClientResult> RefineSharded(
    const std::vector<std::shared_ptr<grpc::Channel>>& targets, const Volume& volume,
    const Mesh& mesh, const client::RefineRequestOptions& options, int shards,
    const client::RefineCallbacks& callbacks = {}, const client::CallOptions& call = {},
    const std::vector<std::string>& target_names = {}, const std::vector<int>& max_open_calls = {});

// As RefineSharded, with ShardOptions::keep_pieces: the whole ShardedResult, whose reply has no
// mesh and whose pieces hold the result (for a .pvtu written piece by piece).
absl::StatusOr<ShardedResult> RefineShardedInPieces(
    const std::vector<std::shared_ptr<grpc::Channel>>& targets, const Volume& volume,
    const Mesh& mesh, const client::RefineRequestOptions& options, int shards,
    const client::RefineCallbacks& callbacks = {}, const client::CallOptions& call = {},
    const std::vector<std::string>& target_names = {}, const std::vector<int>& max_open_calls = {});

// One channel per address ("host:port", or any gRPC target such as "dns:///name:port").
std::vector<std::shared_ptr<grpc::Channel>> ChannelsFor(
    const std::vector<std::string>& addresses,
    const std::shared_ptr<grpc::ChannelCredentials>& credentials);

}  // namespace tetrefine::sharding
