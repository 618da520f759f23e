// libFuzzer target: the client's side of a Refine call. The input is a sequence of serialized
// RefineResponse messages (2-byte little-endian length, message, repeated), as a broken or
// hostile server might send them, fed to wire::ResponseReader; the first byte says whether the
// final mesh was asked for. Errors are fine; a crash, or a reply that breaks the reader's own
// promises (indices in range, per-tet arrays as long as the tets), is not.

#include <string>

#include "absl/strings/str_cat.h"
#include "fuzz/fuzz_support.h"
#include "wire/response_reader.h"

namespace tetrefine::fuzz {
namespace {

void CheckMesh(const Mesh& mesh, const std::vector<int32_t>& iterations,
               const std::vector<float>& qualities) {
  for (const Tet& tet : mesh.tets) {
    for (uint32_t v : tet) {
      TETREFINE_FUZZ_CHECK(v < mesh.points.size(), absl::StrCat("vertex ", v, " out of range"));
    }
  }
  TETREFINE_FUZZ_CHECK(mesh.values.empty() || mesh.values.size() == mesh.points.size(),
                       "values neither absent nor one per vertex");
  TETREFINE_FUZZ_CHECK(iterations.empty() || iterations.size() == mesh.tets.size(),
                       "tet_iteration neither absent nor one per tet");
  TETREFINE_FUZZ_CHECK(qualities.empty() || qualities.size() == mesh.tets.size(),
                       "tet_quality neither absent nor one per tet");
}

}  // namespace
}  // namespace tetrefine::fuzz

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace tetrefine;  // NOLINT: a fuzz entry point
  fuzz::ByteSource source(data, size);
  const bool expect_final_mesh = source.Byte() & 1;
  wire::ResponseReader reader(
      nullptr, [](int, const Mesh& mesh) { fuzz::CheckMesh(mesh, {}, {}); }, expect_final_mesh);
  while (source.remaining() > 0 && !reader.complete()) {
    const std::string_view bytes = source.Bytes(source.U16());
    v1::RefineResponse response;
    if (!response.ParseFromArray(bytes.data(), static_cast<int>(bytes.size()))) return 0;
    const absl::Status status = reader.Add(response);
    if (!status.ok()) {
      TETREFINE_FUZZ_CHECK(!status.message().empty(), "an error without a message");
      return 0;
    }
  }
  if (!reader.complete()) return 0;
  const wire::RefineReply reply = reader.Take();
  fuzz::CheckMesh(reply.result.mesh, reply.result.tet_iteration, reply.result.tet_quality);
  return 0;
}
