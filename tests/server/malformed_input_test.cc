// Every malformed request gets INVALID_ARGUMENT with a message naming the field and the index or
// value, and the server keeps serving good requests afterwards.

#include <cmath>
#include <functional>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "client/refine_client.h"
#include "gmock/gmock.h"
#include "gtest/gtest.h"
#include "tests/server/service_test_support.h"
#include "wire/request_writer.h"

namespace tetrefine::testing {
namespace {

using Requests = std::vector<v1::RefineRequest>;
using Kind = v1::RefineRequest::KindCase;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// 10^3 float64 voxels in 200-byte chunks (40 of them), 27 vertices in chunks of 8, 40 tets in
// chunks of 12: every kind of chunk comes several times.
const Volume& SmallVolume() {
  static const Volume* volume = new Volume(TestVolume({10, 10, 10}));
  return *volume;
}
const Mesh& SmallMesh() {
  static const Mesh* mesh = new Mesh(FiveTetMesh({1.0, 1.0, 1.0}, {8.0, 8.0, 8.0}, {2, 2, 2}));
  return *mesh;
}

Requests ValidRequests() {
  Requests requests;
  RefineOptions options;
  options.epsilon = 0.05;
  options.max_iterations = 2;
  wire::WriteRequest(wire::RequestOptionsFromCore(options), SmallVolume(), SmallMesh(), 200,
                     [&](const v1::RefineRequest& r) {
                       requests.push_back(r);
                       return true;
                     });
  return requests;
}

// Position of the n-th message of `kind`.
size_t Find(const Requests& requests, Kind kind, int n = 0) {
  for (size_t i = 0; i < requests.size(); ++i) {
    if (requests[i].kind_case() == kind && n-- == 0) return i;
  }
  ADD_FAILURE() << "no message " << n << " of kind " << kind;
  return 0;
}
size_t FindLast(const Requests& requests, Kind kind) {
  for (size_t i = requests.size(); i-- > 0;) {
    if (requests[i].kind_case() == kind) return i;
  }
  ADD_FAILURE() << "no message of kind " << kind;
  return 0;
}

v1::RefineOptions& Options(Requests& r) { return *r[0].mutable_options(); }
v1::VolumeHeader& VolumeHeader(Requests& r) {
  return *r[Find(r, Kind::kVolumeHeader)].mutable_volume_header();
}
v1::MeshHeader& MeshHeader(Requests& r) {
  return *r[Find(r, Kind::kMeshHeader)].mutable_mesh_header();
}

struct Malformation {
  std::string name;
  std::function<void(Requests&)> mutate;
  std::vector<std::string> message_parts;  // each must appear in the status message
  grpc::StatusCode code = grpc::StatusCode::INVALID_ARGUMENT;
};

std::vector<Malformation> Malformations() {
  return {
      // Order and presence of the stream's parts.
      {"EmptyStream", [](Requests& r) { r.clear(); }, {"options: missing"}},
      {"OptionsNotFirst",
       [](Requests& r) { std::swap(r[0], r[1]); },
       {"expected options (it must come first)", "got volume_header"}},
      {"OptionsMissing",
       [](Requests& r) { r.erase(r.begin()); },
       {"expected options", "got volume_header"}},
      {"OptionsTwice",
       [](Requests& r) { r.insert(r.begin() + 1, r[0]); },
       {"expected volume_header", "got options"}},
      {"UnknownKind",
       [](Requests& r) { r.insert(r.begin() + 2, v1::RefineRequest()); },
       {"message 2", "no known kind"}},
      {"EndOfInputMissing", [](Requests& r) { r.pop_back(); }, {"end_of_input: missing"}},
      {"MeshHeaderBeforeVolumeEnds",
       [](Requests& r) { r.erase(r.begin() + FindLast(r, Kind::kVolumeChunk)); },
       {"expected volume_chunk", "still missing", "got mesh_header"}},
      // Options.
      {"EpsilonZero",
       [](Requests& r) { Options(r).set_epsilon(0.0); },
       {"options.epsilon", "got 0"}},
      {"EpsilonNegative",
       [](Requests& r) { Options(r).set_epsilon(-0.5); },
       {"options.epsilon", "got -0.5"}},
      {"EpsilonNaN", [](Requests& r) { Options(r).set_epsilon(kNaN); }, {"options.epsilon", "nan"}},
      {"MaxIterationsNegative",
       [](Requests& r) { Options(r).set_max_iterations(-1); },
       {"options.max_iterations", "got -1"}},
      {"MaxTetsZero",
       [](Requests& r) { Options(r).set_max_tets(0); },
       {"options.max_tets", "got 0"}},
      {"NormCoeffZero",
       [](Requests& r) { Options(r).set_norm_coeff(0.0); },
       {"options.norm_coeff", "got 0"}},
      {"OutsidePolicyUnknown",
       [](Requests& r) { Options(r).set_outside_policy(static_cast<v1::OutsidePolicy>(9)); },
       {"options.outside_policy", "unknown value 9"}},
      {"OrientationPolicyUnknown",
       [](Requests& r) {
         Options(r).set_orientation_policy(static_cast<v1::OrientationPolicy>(-3));
       },
       {"options.orientation_policy", "unknown value -3"}},
      {"LatticeNNegative",
       [](Requests& r) { Options(r).set_lattice_n(-2); },
       {"options.lattice_n", "got -2"}},
      {"LatticeNTooLargeForCore",
       [](Requests& r) { Options(r).set_lattice_n(1000); },
       {"options.lattice_n", "1000"}},
      {"MinQualityOne",
       [](Requests& r) { Options(r).set_min_quality(1.0); },
       {"options.min_quality", "got 1"}},
      {"MinEdgeLengthNegative",
       [](Requests& r) { Options(r).set_min_edge_length(-1.0); },
       {"options.min_edge_length", "got -1"}},
      {"InputTetsAboveMaxTets",
       [](Requests& r) { Options(r).set_max_tets(10); },
       {"mesh_header.tet_count: 40 exceeds options.max_tets = 10"}},
      // Volume header.
      {"DimsMissing",
       [](Requests& r) { VolumeHeader(r).clear_dims(); },
       {"volume_header.dims: missing"}},
      {"DimsTooSmall",
       [](Requests& r) { VolumeHeader(r).mutable_dims()->set_y(1); },
       {"volume_header.dims.y", "got 1"}},
      {"SlabLoNegative",
       [](Requests& r) { VolumeHeader(r).mutable_slab_lo()->set_x(-1); },
       {"volume_header.slab_lo.x", "got -1"}},
      {"SlabHiBeyondDims",
       [](Requests& r) { VolumeHeader(r).mutable_slab_hi()->set_z(11); },
       {"volume_header.slab_hi.z", "got 11"}},
      {"SpacingNaN",
       [](Requests& r) { VolumeHeader(r).mutable_spacing()->set_x(kNaN); },
       {"volume_header.spacing.x", "nan"}},
      {"SpacingZero",
       [](Requests& r) { VolumeHeader(r).mutable_spacing()->set_z(0.0); },
       {"volume_header.spacing.z", "got 0"}},
      {"OriginInfinite",
       [](Requests& r) {
         VolumeHeader(r).mutable_origin()->set_y(std::numeric_limits<double>::infinity());
       },
       {"volume_header.origin.y", "inf"}},
      {"VoxelTypeUnknown",
       [](Requests& r) { VolumeHeader(r).set_voxel_type(static_cast<v1::VoxelType>(42)); },
       {"volume_header.voxel_type", "42"}},
      {"VoxelTypeUnspecified",
       [](Requests& r) { VolumeHeader(r).set_voxel_type(v1::VOXEL_TYPE_UNSPECIFIED); },
       {"volume_header.voxel_type", "voxel type 0"}},
      {"TotalBytesWrong",
       [](Requests& r) { VolumeHeader(r).set_total_bytes(8001); },
       {"volume_header.total_bytes: expected 8000", "got 8001"}},
      // Volume chunks.
      {"VolumeChunksSwapped",
       [](Requests& r) {
         std::swap(r[Find(r, Kind::kVolumeChunk, 2)], r[Find(r, Kind::kVolumeChunk, 3)]);
       },
       {"volume_chunk.offset: expected 400", "got 600"}},
      {"VolumeChunkOverlaps",
       [](Requests& r) {
         r[Find(r, Kind::kVolumeChunk, 3)].mutable_volume_chunk()->set_offset(599);
       },
       {"volume_chunk.offset: expected 600", "got 599"}},
      {"VolumeChunkMissing",
       [](Requests& r) { r.erase(r.begin() + Find(r, Kind::kVolumeChunk, 2)); },
       {"volume_chunk.offset: expected 400", "got 600"}},
      {"VolumeChunkEmpty",
       [](Requests& r) { r[Find(r, Kind::kVolumeChunk, 1)].mutable_volume_chunk()->clear_data(); },
       {"volume_chunk.data: empty at offset 200"}},
      {"VolumeChunkTooLong",
       [](Requests& r) {
         r[FindLast(r, Kind::kVolumeChunk)].mutable_volume_chunk()->mutable_data()->append("x");
       },
       {"volume_chunk.data: 201 bytes at offset 7800", "volume_header.total_bytes = 8000"}},
      // Mesh header and chunks.
      {"TetCountNegative",
       [](Requests& r) { MeshHeader(r).set_tet_count(-5); },
       {"mesh_header.tet_count", "got -5"}},
      {"VertexCountTooSmall",
       [](Requests& r) { MeshHeader(r).set_vertex_count(26); },
       {"vertex_chunk.coordinates: 3 vertices at start_index 24", "mesh_header.vertex_count = 26"}},
      {"VertexCountTooLarge",
       [](Requests& r) { MeshHeader(r).set_vertex_count(28); },
       {"vertex_chunk: received 27 vertices, mesh_header.vertex_count = 28"}},
      {"VertexNaN",
       [](Requests& r) {
         r[Find(r, Kind::kVertexChunk, 1)].mutable_vertex_chunk()->set_coordinates(5 * 3 + 1, kNaN);
       },
       {"vertex_chunk.coordinates: vertex 13", "non-finite y coordinate"}},
      {"VertexChunkRagged",
       [](Requests& r) {
         r[Find(r, Kind::kVertexChunk, 1)]
             .mutable_vertex_chunk()
             ->mutable_coordinates()
             ->RemoveLast();
       },
       {"vertex_chunk.coordinates", "multiple of 3", "got 23 at start_index 8"}},
      {"VertexChunksSwapped",
       [](Requests& r) {
         std::swap(r[Find(r, Kind::kVertexChunk, 0)], r[Find(r, Kind::kVertexChunk, 1)]);
       },
       {"vertex_chunk.start_index: expected 0", "got 8"}},
      {"VertexChunkMissing",
       [](Requests& r) { r.erase(r.begin() + Find(r, Kind::kVertexChunk, 1)); },
       {"vertex_chunk.start_index: expected 8", "got 16"}},
      {"TetIndexOutOfRange",
       [](Requests& r) {
         r[Find(r, Kind::kTetChunk, 1)].mutable_tet_chunk()->set_indices(5 * 4 + 2, 27);
       },
       {"tet_chunk.indices: tet 17 corner 2 is vertex 27", "mesh_header.vertex_count = 27"}},
      {"TetChunkRagged",
       [](Requests& r) {
         r[Find(r, Kind::kTetChunk, 0)].mutable_tet_chunk()->mutable_indices()->RemoveLast();
       },
       {"tet_chunk.indices", "multiple of 4", "got 47 at start_index 0"}},
      {"TetChunkOverlaps",
       [](Requests& r) { r[Find(r, Kind::kTetChunk, 2)].mutable_tet_chunk()->set_start_index(23); },
       {"tet_chunk.start_index: expected 24", "got 23"}},
      {"TetsMissing",
       [](Requests& r) { r.erase(r.begin() + FindLast(r, Kind::kTetChunk)); },
       {"tet_chunk: received 36 tets, mesh_header.tet_count = 40"}},
      {"ValuesNotAnnounced",
       [](Requests& r) {
         v1::RefineRequest values;
         values.mutable_value_chunk()->add_values(1.0);
         r.insert(r.end() - 1, values);
       },
       {"value_chunk: not expected", "mesh_header.has_values is false"}},
      {"ValueNaN",
       [](Requests& r) {
         MeshHeader(r).set_has_values(true);
         v1::RefineRequest values;
         for (int i = 0; i < 27; ++i) values.mutable_value_chunk()->add_values(i == 3 ? kNaN : 1.0);
         r.insert(r.end() - 1, values);
       },
       {"value_chunk.values: vertex 3", "non-finite"}},
      {"EmptyMesh",
       [](Requests& r) {
         MeshHeader(r).set_vertex_count(0);
         MeshHeader(r).set_tet_count(0);
         std::erase_if(r, [](const v1::RefineRequest& m) {
           return m.has_vertex_chunk() || m.has_tet_chunk();
         });
       },
       {"mesh.tets is empty"}},
      // Geometry the core rejects, its message passed through.
      {"VertexOutsideVolume",
       [](Requests& r) {
         r[Find(r, Kind::kVertexChunk, 0)].mutable_vertex_chunk()->set_coordinates(0, -5.0);
       },
       {"mesh.points[0]", "outside"}},
      {"InvertedTet",
       [](Requests& r) {
         auto* indices = r[Find(r, Kind::kTetChunk, 0)].mutable_tet_chunk()->mutable_indices();
         std::swap(*indices->Mutable(7 * 4 + 2), *indices->Mutable(7 * 4 + 3));
       },
       {"mesh.tets[7]", "inverted"}},
      {"DegenerateTet",
       [](Requests& r) {
         // Vertices 0, 1 and 2 lie on one grid line: the tet is flat.
         auto* indices = r[Find(r, Kind::kTetChunk, 0)].mutable_tet_chunk()->mutable_indices();
         for (int c = 0; c < 4; ++c) indices->Set(7 * 4 + c, static_cast<uint32_t>(c));
       },
       {"mesh.tets[7]", "degenerate"}},
  };
}

class ServiceMalformedInputTest : public ::testing::TestWithParam<Malformation> {
 protected:
  static void SetUpTestSuite() { server_ = new LoopbackServer(); }
  static void TearDownTestSuite() {
    delete server_;
    server_ = nullptr;
  }
  static LoopbackServer* server_;
};
LoopbackServer* ServiceMalformedInputTest::server_ = nullptr;

TEST_P(ServiceMalformedInputTest, IsRejectedNamingTheFieldAndTheServerCarriesOn) {
  const Malformation& m = GetParam();
  Requests requests = ValidRequests();
  m.mutate(requests);
  const grpc::Status status = SendRaw(server_->NewChannel(), requests);
  EXPECT_EQ(status.error_code(), m.code) << status.error_message();
  for (const std::string& part : m.message_parts) {
    EXPECT_THAT(status.error_message(), ::testing::HasSubstr(part));
  }
  const grpc::Status good = SendRaw(server_->NewChannel(), ValidRequests());
  EXPECT_TRUE(good.ok()) << good.error_message();
}

INSTANTIATE_TEST_SUITE_P(All, ServiceMalformedInputTest, ::testing::ValuesIn(Malformations()),
                         [](const ::testing::TestParamInfo<Malformation>& info) {
                           return info.param.name;
                         });

// Random byte flips in random messages: whatever the server makes of them, it answers (never
// crashes) and then serves a good request.
TEST(ServiceFuzzedInputTest, ByteFlipsNeverBreakTheServer) {
  LoopbackServer server;
  std::mt19937_64 rng(20240601);
  const Requests valid = ValidRequests();
  int rejected = 0;
  for (int round = 0; round < 300; ++round) {
    Requests requests = valid;
    const size_t target = rng() % requests.size();
    std::string bytes = requests[target].SerializeAsString();
    if (bytes.empty()) continue;
    for (int flips = 1 + static_cast<int>(rng() % 3); flips > 0; --flips) {
      bytes[rng() % bytes.size()] = static_cast<char>(rng());
    }
    if (!requests[target].ParseFromString(bytes)) continue;
    const grpc::Status status = SendRaw(server.NewChannel(), requests);
    if (!status.ok()) {
      ++rejected;
      EXPECT_THAT(status.error_code(), ::testing::AnyOf(grpc::StatusCode::INVALID_ARGUMENT,
                                                        grpc::StatusCode::RESOURCE_EXHAUSTED))
          << status.error_message();
    }
  }
  EXPECT_GT(rejected, 0);
  EXPECT_TRUE(SendRaw(server.NewChannel(), valid).ok());
}

}  // namespace
}  // namespace tetrefine::testing
