// libFuzzer target: a Refine request stream as the server receives it. The input is a sequence
// of serialized RefineRequest messages, each preceded by its length (2 bytes, little-endian).
// Messages go through wire::RequestReader exactly as the service feeds them; a stream it accepts
// goes on to the core (validation, then a refinement kept small), and the result through the
// response writer and back through the client's response reader, which must reassemble it bit
// for bit.

#include <algorithm>
#include <cstring>
#include <vector>

#include "absl/strings/str_cat.h"
#include "core/refine.h"
#include "fuzz/fuzz_support.h"
#include "wire/conversion.h"
#include "wire/request_reader.h"
#include "wire/response_reader.h"
#include "wire/response_writer.h"

namespace tetrefine::fuzz {
namespace {

// Small, so that declared sizes the reader accepts stay cheap to allocate; the checks are the
// same code whatever the numbers.
wire::ServiceLimits FuzzLimits() {
  wire::ServiceLimits limits;
  limits.max_voxels = 1 << 14;
  limits.max_input_tets = 512;
  limits.max_output_tets = 4096;
  return limits;
}

template <typename T>
bool SameBits(const std::vector<T>& a, const std::vector<T>& b) {
  return a.size() == b.size() &&
         (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(T)) == 0);
}

// Refines the accepted input (bounded) and checks that the response stream carries the result
// intact.
void RefineAndRoundTrip(const wire::RefineInput& input, const wire::ServiceLimits& limits) {
  RefineOptions options = wire::ToCoreOptions(input.options, limits);
  options.threads = 1;
  options.max_iterations = std::min(options.max_iterations, 2);
  options.max_tets = std::min<int64_t>(options.max_tets, 4096);
  options.lattice_n = std::min(options.lattice_n, 4);
  options.lattice_max_tets = std::min<int64_t>(options.lattice_max_tets, 32);
  std::vector<v1::RefineResponse> responses;
  wire::ResponseWriter writer(input.options.response_chunk_bytes, [&](const v1::RefineResponse& r) {
    responses.push_back(r);
    return true;
  });
  options.on_iteration = [&](const IterationStats& stats, const Mesh& mesh) {
    writer.WriteIterationStats(stats);
    if (input.options.stream_every_iteration)
      writer.WriteMesh(stats.iteration, false, mesh, {}, {});
  };
  absl::StatusOr<RefineResult> result = Refine(input.volume, input.mesh, options);
  if (!result.ok()) {
    TETREFINE_FUZZ_CHECK(absl::IsInvalidArgument(result.status()), result.status().ToString());
    return;
  }
  const int iterations = static_cast<int>(result->iterations.size());
  if (!input.options.skip_final_mesh) {
    writer.WriteMesh(iterations, true, result->mesh, result->tet_iteration, result->tet_quality);
  }
  writer.WriteSummary(*result, {.max_tets = options.max_tets},
                      static_cast<int64_t>(input.mesh.tets.size()));

  wire::ResponseReader reader(nullptr, nullptr, !input.options.skip_final_mesh);
  for (const v1::RefineResponse& response : responses) {
    const absl::Status status = reader.Add(response);
    TETREFINE_FUZZ_CHECK(status.ok(), status.ToString());
  }
  TETREFINE_FUZZ_CHECK(reader.complete(), "the response stream did not complete");
  const wire::RefineReply reply = reader.Take();
  TETREFINE_FUZZ_CHECK(reply.result.iterations.size() == result->iterations.size(),
                       "iteration count changed on the wire");
  if (!input.options.skip_final_mesh) {
    TETREFINE_FUZZ_CHECK(SameBits(reply.result.mesh.points, result->mesh.points),
                         "points changed on the wire");
    TETREFINE_FUZZ_CHECK(SameBits(reply.result.mesh.tets, result->mesh.tets),
                         "tets changed on the wire");
    TETREFINE_FUZZ_CHECK(SameBits(reply.result.mesh.values, result->mesh.values),
                         "values changed on the wire");
    TETREFINE_FUZZ_CHECK(SameBits(reply.result.tet_quality, result->tet_quality),
                         "tet_quality changed on the wire");
  }
}

}  // namespace
}  // namespace tetrefine::fuzz

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace tetrefine;  // NOLINT: a fuzz entry point
  fuzz::ByteSource source(data, size);
  const wire::ServiceLimits limits = fuzz::FuzzLimits();
  wire::RequestReader reader(limits);
  // A real stream is bounded by what the client sends; the fuzzer's by its input size.
  while (source.remaining() > 0 && !reader.complete()) {
    const std::string_view bytes = source.Bytes(source.U16());
    v1::RefineRequest request;
    if (!request.ParseFromArray(bytes.data(), static_cast<int>(bytes.size()))) return 0;
    const absl::Status status = reader.Add(request);
    if (!status.ok()) {
      TETREFINE_FUZZ_CHECK(absl::IsInvalidArgument(status) || absl::IsResourceExhausted(status),
                           status.ToString());
      TETREFINE_FUZZ_CHECK(!status.message().empty(), "an error without a message");
      return 0;
    }
  }
  if (!reader.complete()) {
    const absl::Status incomplete = reader.IncompleteError();
    TETREFINE_FUZZ_CHECK(absl::IsInvalidArgument(incomplete), incomplete.ToString());
    return 0;
  }
  const wire::RefineInput input = reader.Take();
  TETREFINE_FUZZ_CHECK(input.volume.voxel_count() <= limits.max_voxels, "volume above the limit");
  TETREFINE_FUZZ_CHECK(static_cast<int64_t>(input.mesh.tets.size()) <= limits.max_input_tets,
                       "mesh above the limit");
  for (const Tet& tet : input.mesh.tets) {
    for (uint32_t v : tet) {
      TETREFINE_FUZZ_CHECK(v < input.mesh.points.size(), "the reader let an index through");
    }
  }
  fuzz::RefineAndRoundTrip(input, limits);
  return 0;
}
