#pragma once

// The one table of malformed Refine requests: every way the tests know to break a request
// stream (order, presence, chunk offsets and lengths, declared sizes, absurd sizes, non-finite
// numbers, bad options and enums, indices and tets the core refuses), each with the status code
// and the message parts a server must answer with. tests/server runs it against an in-process
// server, tests/hardening against a tetrefine_server process (watching its memory too).

#include <functional>
#include <ostream>
#include <string>
#include <vector>

#include "core/mesh.h"
#include "core/refine.h"
#include "core/volume.h"
#include "grpcpp/support/status.h"
#include "tetrefine/v1/tetrefine.pb.h"
#include "wire/conversion.h"

namespace tetrefine::testing {

using RefineRequests = std::vector<v1::RefineRequest>;

// The good request every case breaks: TestVolume({10, 10, 10}) (10^3 float64 voxels) and
// FiveTetMesh({1, 1, 1}, {8, 8, 8}, {2, 2, 2}) (27 vertices, 40 tets), written in 200-byte chunks:
// 40 volume chunks, vertices 8 a chunk, tets 12 a chunk, values (when present) 25 a chunk.
const Volume& SmallVolume();
const Mesh& SmallMesh();
// epsilon 0.05, max_iterations 2; the rest defaults.
RefineOptions SmallRefineOptions();
RefineRequests GoodRequests();

struct MalformedRequest {
  std::string name;                          // a GoogleTest parameter name
  std::function<RefineRequests()> requests;  // the broken stream
  std::vector<std::string> message_parts;    // each must appear in the status message
  grpc::StatusCode code = grpc::StatusCode::INVALID_ARGUMENT;
};
// Names the case in test listings (GoogleTest would print its bytes).
void PrintTo(const MalformedRequest& c, std::ostream* os);

std::vector<MalformedRequest> MalformedRequests();

}  // namespace tetrefine::testing
