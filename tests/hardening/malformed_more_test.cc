// Malformed requests beyond tests/server/malformed_input_test.cc, sent to a real tetrefine_server
// process: truncated streams at every stage, chunks duplicated or out of order for every kind,
// declared sizes that disagree with the data, absurd declared sizes, non-finite numbers wherever
// a number goes, repeated vertices, a non-manifold mesh, a mesh outside its slab, empty meshes,
// and bytes that are not a RefineRequest at all. Each gets the right status code and a message
// naming the problem, and the same server process then serves a good request correctly.

#include <chrono>
#include <cmath>
#include <functional>
#include <limits>
#include <map>
#include <ostream>
#include <random>
#include <string>
#include <vector>

#include "client/refine_client.h"
#include "gmock/gmock.h"
#include "gtest/gtest.h"
#include "tests/hardening/raw_call.h"
#include "tests/hardening/server_process.h"
#include "tests/hardening/workloads.h"
#include "tests/server/service_test_support.h"
#include "wire/request_writer.h"

namespace tetrefine::hardening {
namespace {

using ::tetrefine::testing::FiveTetMesh;
using ::tetrefine::testing::SendRaw;
using ::tetrefine::testing::TestSlab;
using ::tetrefine::testing::TestVolume;

using ::testing::HasSubstr;
using Requests = std::vector<v1::RefineRequest>;
using Kind = v1::RefineRequest::KindCase;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

// As in malformed_input_test: 10^3 float64 voxels in 200-byte chunks (40), 27 vertices in chunks
// of 8, 40 tets in chunks of 12, and here also 27 values in chunks of 25.
const Volume& SmallVolume() {
  static const Volume* volume = new Volume(TestVolume({10, 10, 10}));
  return *volume;
}
const Mesh& SmallMesh() {
  static const Mesh* mesh = new Mesh(FiveTetMesh({1.0, 1.0, 1.0}, {8.0, 8.0, 8.0}, {2, 2, 2}));
  return *mesh;
}

Requests Write(const Volume& volume, const Mesh& mesh, wire::RequestOptions options = {}) {
  options.epsilon = 0.05;
  options.max_iterations = 2;
  Requests requests;
  wire::WriteRequest(options, volume, mesh, 200, [&](const v1::RefineRequest& r) {
    requests.push_back(r);
    return true;
  });
  return requests;
}
Requests ValidRequests() { return Write(SmallVolume(), SmallMesh()); }
Requests WithValues() {
  Mesh mesh = SmallMesh();
  for (size_t i = 0; i < mesh.points.size(); ++i) mesh.values.push_back(0.1 * i);
  return Write(SmallVolume(), mesh);
}

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
void CutAfter(Requests& r, size_t index) { r.resize(index + 1); }
void Duplicate(Requests& r, size_t index) { r.insert(r.begin() + index + 1, r[index]); }

v1::RefineOptions& Options(Requests& r) { return *r[0].mutable_options(); }
v1::VolumeHeader& VolumeHeader(Requests& r) {
  return *r[Find(r, Kind::kVolumeHeader)].mutable_volume_header();
}
v1::MeshHeader& MeshHeader(Requests& r) {
  return *r[Find(r, Kind::kMeshHeader)].mutable_mesh_header();
}
v1::TetChunk& TetChunk(Requests& r, int n) {
  return *r[Find(r, Kind::kTetChunk, n)].mutable_tet_chunk();
}
void SetTet(Requests& r, int tet, const Tet& corners) {
  // Tets travel 12 to a chunk.
  for (int c = 0; c < 4; ++c) TetChunk(r, tet / 12).set_indices((tet % 12) * 4 + c, corners[c]);
}

// The small mesh plus one tet on an interior face (a face two tets already share) and a new
// vertex just beside it, oriented positively: that face then lies in three tets.
Mesh NonManifoldMesh() {
  Mesh mesh = SmallMesh();
  std::map<std::array<uint32_t, 3>, int> uses;
  for (const Tet& t : mesh.tets) {
    for (int skip = 0; skip < 4; ++skip) {
      std::array<uint32_t, 3> face{};
      for (int i = 0, k = 0; i < 4; ++i) {
        if (i != skip) face[k++] = t[i];
      }
      std::sort(face.begin(), face.end());
      ++uses[face];
    }
  }
  for (const auto& [face, count] : uses) {
    if (count != 2) continue;
    Vec3 centre{0.0, 0.0, 0.0};
    for (uint32_t v : face) {
      for (int a = 0; a < 3; ++a) centre[a] += mesh.points[v][a] / 3.0;
    }
    centre[0] += 0.3;
    centre[1] += 0.2;
    centre[2] += 0.1;
    mesh.points.push_back(centre);
    Tet tet{face[0], face[1], face[2], static_cast<uint32_t>(mesh.points.size() - 1)};
    if (SignedVolume6(mesh.points[tet[0]], mesh.points[tet[1]], mesh.points[tet[2]],
                      mesh.points[tet[3]]) < 0) {
      std::swap(tet[0], tet[1]);
    }
    mesh.tets.push_back(tet);
    return mesh;
  }
  ADD_FAILURE() << "no interior face";
  return mesh;
}

struct Case {
  std::string name;
  std::function<Requests()> requests;
  std::vector<std::string> message_parts;
  grpc::StatusCode code = grpc::StatusCode::INVALID_ARGUMENT;
};

// Names the case in test listings (gtest would print its bytes).
void PrintTo(const Case& c, std::ostream* os) { *os << c.name; }

// A case built by editing the valid stream.
Case Edit(std::string name, std::function<void(Requests&)> edit, std::vector<std::string> parts,
          grpc::StatusCode code = grpc::StatusCode::INVALID_ARGUMENT) {
  return {std::move(name),
          [edit] {
            Requests r = ValidRequests();
            edit(r);
            return r;
          },
          std::move(parts), code};
}

std::vector<Case> Cases() {
  const auto kExhausted = grpc::StatusCode::RESOURCE_EXHAUSTED;
  return {
      // Truncated at every stage.
      Edit("TruncatedAfterOptions", [](Requests& r) { CutAfter(r, 0); },
           {"volume_header: missing"}),
      Edit("TruncatedAfterVolumeHeader",
           [](Requests& r) { CutAfter(r, Find(r, Kind::kVolumeHeader)); },
           {"volume_chunk: stream ended after 0 of volume_header.total_bytes = 8000 bytes"}),
      Edit("TruncatedInsideVolume",
           [](Requests& r) { CutAfter(r, Find(r, Kind::kVolumeChunk, 2)); },
           {"volume_chunk: stream ended after 600 of volume_header.total_bytes = 8000 bytes"}),
      Edit("TruncatedAfterVolume",
           [](Requests& r) { CutAfter(r, FindLast(r, Kind::kVolumeChunk)); },
           {"mesh_header: missing"}),
      Edit("TruncatedInsideMesh", [](Requests& r) { CutAfter(r, Find(r, Kind::kTetChunk, 1)); },
           {"end_of_input: missing"}),
      // Out of order, duplicated or missing, for every kind of chunk and header.
      Edit("TetChunksSwapped",
           [](Requests& r) {
             std::swap(r[Find(r, Kind::kTetChunk, 1)], r[Find(r, Kind::kTetChunk, 2)]);
           },
           {"tet_chunk.start_index: expected 12", "got 24"}),
      {"ValueChunksSwapped",
       [] {
         Requests r = WithValues();
         std::swap(r[Find(r, Kind::kValueChunk, 0)], r[Find(r, Kind::kValueChunk, 1)]);
         return r;
       },
       {"value_chunk.start_index: expected 0", "got 25"}},
      Edit("VolumeChunkDuplicated",
           [](Requests& r) { Duplicate(r, Find(r, Kind::kVolumeChunk, 1)); },
           {"volume_chunk.offset: expected 400", "got 200"}),
      Edit("VertexChunkDuplicated",
           [](Requests& r) { Duplicate(r, Find(r, Kind::kVertexChunk, 0)); },
           {"vertex_chunk.start_index: expected 8", "got 0"}),
      Edit("TetChunkDuplicated", [](Requests& r) { Duplicate(r, FindLast(r, Kind::kTetChunk)); },
           {"tet_chunk.start_index: expected 40", "got 36"}),
      {"ValueChunkDuplicated",
       [] {
         Requests r = WithValues();
         Duplicate(r, Find(r, Kind::kValueChunk, 0));
         return r;
       },
       {"value_chunk.start_index: expected 25", "got 0"}},
      Edit("VolumeHeaderTwice", [](Requests& r) { Duplicate(r, Find(r, Kind::kVolumeHeader)); },
           {"expected volume_chunk", "got volume_header"}),
      Edit("MeshHeaderTwice", [](Requests& r) { Duplicate(r, Find(r, Kind::kMeshHeader)); },
           {"expected vertex_chunk, value_chunk, tet_chunk or end_of_input", "got mesh_header"}),
      Edit("TetChunkMissing", [](Requests& r) { r.erase(r.begin() + Find(r, Kind::kTetChunk, 1)); },
           {"tet_chunk.start_index: expected 12", "got 24"}),
      {"ValuesMissing",
       [] {
         Requests r = ValidRequests();
         MeshHeader(r).set_has_values(true);
         return r;
       },
       {"value_chunk: received 0 values, mesh_header.vertex_count = 27"}},
      // Declared sizes that disagree with the data.
      Edit("TetCountTooLarge", [](Requests& r) { MeshHeader(r).set_tet_count(41); },
           {"tet_chunk: received 40 tets, mesh_header.tet_count = 41"}),
      Edit("TetCountTooSmall", [](Requests& r) { MeshHeader(r).set_tet_count(39); },
           {"tet_chunk.indices: 4 tets at start_index 36 run past mesh_header.tet_count = 39"}),
      Edit("TotalBytesTooSmall", [](Requests& r) { VolumeHeader(r).set_total_bytes(7999); },
           {"volume_header.total_bytes: expected 8000", "got 7999"}),
      Edit("DimsLargerThanData",
           [](Requests& r) {
             VolumeHeader(r).mutable_dims()->set_x(11);
             VolumeHeader(r).mutable_slab_hi()->set_x(11);
           },
           {"volume_header.total_bytes: expected 8800", "got 8000"}),
      Edit("TotalBytesAbsurd", [](Requests& r) { VolumeHeader(r).set_total_bytes(~uint64_t{0}); },
           {"volume_header.total_bytes: expected 8000", "got 18446744073709551615"}),
      // Absurd declared sizes: refused at the header, before anything of that size exists.
      Edit(
          "MillionCubedVoxels",
          [](Requests& r) {
            v1::VolumeHeader& h = VolumeHeader(r);
            for (auto* i : {h.mutable_dims(), h.mutable_slab_hi()}) {
              i->set_x(1'000'000);
              i->set_y(1'000'000);
              i->set_z(1'000'000);
            }
            h.set_total_bytes(uint64_t{8'000'000'000'000'000'000});
          },
          {"volume_header", "more than this server's limit of 268435456 voxels"}, kExhausted),
      Edit("DimsAboveTwoToThe31",
           [](Requests& r) {
             VolumeHeader(r).mutable_dims()->set_z((int64_t{1} << 31) + 1);
             VolumeHeader(r).clear_slab_hi();
           },
           {"volume_header.dims.z: must be in [2, 2147483648], got 2147483649"}),
      // A small slab of a grid too large for the core's index arithmetic: refused once the data
      // is in, by the core, naming the axis.
      Edit("SlabOfAGridAboveTwoToThe20",
           [](Requests& r) { VolumeHeader(r).mutable_dims()->set_y((int64_t{1} << 20) + 1); },
           {"volume.dims.y = 1048577: must be in [2, 2^20]"}),
      Edit(
          "TwoToThe32Tets", [](Requests& r) { MeshHeader(r).set_tet_count(int64_t{1} << 32); },
          {"mesh_header.tet_count: 4294967296 exceeds this server's limit of 10000000"},
          kExhausted),
      Edit(
          "TwoToThe32Vertices",
          [](Requests& r) { MeshHeader(r).set_vertex_count(int64_t{1} << 32); },
          {"mesh_header.vertex_count: 4294967296 exceeds this server's limit of 40000000"},
          kExhausted),
      Edit(
          "MaxInt64Vertices",
          [](Requests& r) { MeshHeader(r).set_vertex_count(std::numeric_limits<int64_t>::max()); },
          {"mesh_header.vertex_count: 9223372036854775807 exceeds"}, kExhausted),
      Edit(
          "MaxTetsAbsurd", [](Requests& r) { Options(r).set_max_tets(int64_t{1} << 62); },
          {"options.max_tets: 4611686018427387904 exceeds this server's limit"}, kExhausted),
      // Non-finite numbers wherever a number goes.
      Edit("VertexInfinite",
           [](Requests& r) {
             r[Find(r, Kind::kVertexChunk, 2)].mutable_vertex_chunk()->set_coordinates(2, kInf);
           },
           {"vertex_chunk.coordinates: vertex 16 has a non-finite z coordinate (inf)"}),
      Edit("VertexMinusInfinite",
           [](Requests& r) {
             r[Find(r, Kind::kVertexChunk, 0)].mutable_vertex_chunk()->set_coordinates(0, -kInf);
           },
           {"vertex 0 has a non-finite x coordinate (-inf)"}),
      {"ValueInfinite",
       [] {
         Requests r = WithValues();
         r[Find(r, Kind::kValueChunk, 1)].mutable_value_chunk()->set_values(1, kInf);
         return r;
       },
       {"value_chunk.values: vertex 26 has a non-finite value (inf)"}},
      Edit("SpacingInfinite", [](Requests& r) { VolumeHeader(r).mutable_spacing()->set_y(kInf); },
           {"volume_header.spacing.y: must be finite and > 0, got inf"}),
      Edit("OriginNaN", [](Requests& r) { VolumeHeader(r).mutable_origin()->set_z(kNaN); },
           {"volume_header.origin.z: must be finite", "nan"}),
      Edit("EpsilonInfinite", [](Requests& r) { Options(r).set_epsilon(kInf); },
           {"options.epsilon: must be finite and > 0, got inf"}),
      Edit("NormCoeffNaN", [](Requests& r) { Options(r).set_norm_coeff(kNaN); },
           {"options.norm_coeff", "nan"}),
      Edit("MinEdgeLengthInfinite", [](Requests& r) { Options(r).set_min_edge_length(kInf); },
           {"options.min_edge_length", "inf"}),
      Edit("MinQualityNaN", [](Requests& r) { Options(r).set_min_quality(kNaN); },
           {"options.min_quality", "nan"}),
      Edit("MinQualityNegative", [](Requests& r) { Options(r).set_min_quality(-0.5); },
           {"options.min_quality: must be in [0, 1), got -0.5"}),
      Edit("MaxIterationsMostNegative",
           [](Requests& r) { Options(r).set_max_iterations(std::numeric_limits<int32_t>::min()); },
           {"options.max_iterations: must be >= 0, got -2147483648"}),
      Edit("LatticeMaxTetsNegative", [](Requests& r) { Options(r).set_lattice_max_tets(-1); },
           {"options.lattice_max_tets: must be >= 0, got -1"}),
      Edit("VoxelTypeNegative",
           [](Requests& r) { VolumeHeader(r).set_voxel_type(static_cast<v1::VoxelType>(-1)); },
           {"volume_header.voxel_type", "-1"}),
      Edit("OutsidePolicyHuge",
           [](Requests& r) {
             Options(r).set_outside_policy(static_cast<v1::OutsidePolicy>(1 << 30));
           },
           {"options.outside_policy: unknown value 1073741824"}),
      // Indices and tets the core refuses.
      Edit("TetIndexMaxUint32", [](Requests& r) { TetChunk(r, 0).set_indices(1, 0xffffffffu); },
           {"tet_chunk.indices: tet 0 corner 1 is vertex 4294967295, out of range"}),
      Edit("RepeatedVertex",
           [](Requests& r) {
             SetTet(r, 7, {5, 9, 5, 13});
           },
           {"mesh.tets[7] repeats vertex 5"}),
      Edit("AllFourVerticesSame",
           [](Requests& r) {
             SetTet(r, 30, {4, 4, 4, 4});
           },
           {"mesh.tets[30] repeats vertex 4"}),
      // Vertices 0, 1, 3 and 4 are four corners of one square of the z = 1 plane.
      Edit("CoplanarTet",
           [](Requests& r) {
             SetTet(r, 3, {0, 1, 3, 4});
           },
           {"mesh.tets[3] is degenerate"}),
      Edit("DuplicatedTet",
           [](Requests& r) {
             const Tet first = SmallMesh().tets[0];
             SetTet(r, 1, first);
           },
           {"overlap"}),
      {"FaceInThreeTets",
       [] { return Write(SmallVolume(), NonManifoldMesh()); },
       {"is shared by 3 tets", "a face may belong to at most two"}},
      // A slab and a mesh that reaches beyond it.
      {"MeshOutsideItsSlab",
       [] {
         return Write(TestSlab({10, 10, 10}, {0, 0, 0}, {10, 10, 5}), SmallMesh());
       },
       {"lies outside the volume's sampled box", "[0, 4]"}},
      {"MeshOutsideItsSlabWhenClamping",
       [] {
         wire::RequestOptions options;
         options.outside = OutsidePolicy::kClamp;
         return Write(TestSlab({10, 10, 10}, {0, 0, 3}, {10, 10, 10}), SmallMesh(), options);
       },
       {"lies outside the volume slab it was sent with"}},
      // Empty meshes.
      Edit("VerticesButNoTets",
           [](Requests& r) {
             MeshHeader(r).set_tet_count(0);
             std::erase_if(r, [](const v1::RefineRequest& m) { return m.has_tet_chunk(); });
           },
           {"mesh.tets is empty"}),
      Edit("TetsButNoVertices",
           [](Requests& r) {
             MeshHeader(r).set_vertex_count(0);
             std::erase_if(r, [](const v1::RefineRequest& m) { return m.has_vertex_chunk(); });
           },
           {"tet_chunk.indices: tet 0 corner 0", "mesh_header.vertex_count = 0"}),
  };
}

class HardeningMalformedTest : public ::testing::TestWithParam<Case> {
 protected:
  static void SetUpTestSuite() {
    std::string error;
    server_ = ServerProcess::Start({"--threads=2"}, 0, &error).release();
    ASSERT_NE(server_, nullptr) << error;
    expected_ = new RefineResult(*Refine(SmallVolume(), SmallMesh(), [] {
      RefineOptions o;
      o.epsilon = 0.05;
      o.max_iterations = 2;
      return o;
    }()));
  }
  static void TearDownTestSuite() {
    if (server_ != nullptr) {
      EXPECT_EQ(server_->Stop(), 0) << server_->process().Output();
    }
    delete server_;
    delete expected_;
    server_ = nullptr;
  }

  // The same process answers a good request with the right result.
  static void ExpectServesAGoodRequest() {
    absl::StatusOr<client::ClientResult> result =
        client::RefineViaService(server_->NewChannel(), SmallVolume(), SmallMesh(), [] {
          client::RefineRequestOptions o;
          o.epsilon = 0.05;
          o.max_iterations = 2;
          return o;
        }());
    ASSERT_TRUE(result.ok()) << result.status();
    EXPECT_EQ(ResultDifference(*expected_, result->result), "");
  }

  static ServerProcess* server_;
  static RefineResult* expected_;
};
ServerProcess* HardeningMalformedTest::server_ = nullptr;
RefineResult* HardeningMalformedTest::expected_ = nullptr;

TEST_P(HardeningMalformedTest, IsRefusedNamingTheProblemAndTheServerCarriesOn) {
  ASSERT_NE(server_, nullptr);
  const Case& c = GetParam();
  const int64_t rss_before = server_->process().RssKb();
  const auto start = std::chrono::steady_clock::now();
  const grpc::Status status = SendRaw(server_->NewChannel(), c.requests());
  EXPECT_EQ(status.error_code(), c.code) << status.error_message();
  for (const std::string& part : c.message_parts) {
    EXPECT_THAT(status.error_message(), HasSubstr(part));
  }
  // Refused from the header: no time or memory spent on what it declared.
  EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::seconds(10));
  EXPECT_LT(server_->process().RssKb() - rss_before, 200 * 1024) << "kB grown";
  ExpectServesAGoodRequest();
}

INSTANTIATE_TEST_SUITE_P(All, HardeningMalformedTest, ::testing::ValuesIn(Cases()),
                         [](const ::testing::TestParamInfo<Case>& info) {
                           return info.param.name;
                         });

// Bytes that do not parse as a RefineRequest, as the first message or after a good start.
TEST_F(HardeningMalformedTest, GarbageBytesAreRefused) {
  ASSERT_NE(server_, nullptr);
  std::vector<std::string> good;
  for (const v1::RefineRequest& r : ValidRequests()) good.push_back(r.SerializeAsString());
  const std::vector<std::string> garbage = {
      std::string("\xff\xff\xff\xff\xff\xff\xff\xff\xff\xff", 10),  // a varint that never ends
      std::string("\x0a\xff\xff\xff\xff\x07", 6),                   // options, 2 GiB long, absent
      std::string("\x12\x05\x0a\x03\x08", 5),                       // volume_header cut inside dims
      "GET / HTTP/1.1\r\n\r\n",
  };
  for (size_t g = 0; g < garbage.size(); ++g) {
    for (size_t at : {size_t{0}, size_t{2}, good.size() - 1}) {
      std::vector<std::string> messages(good.begin(), good.begin() + at);
      messages.push_back(garbage[g]);
      messages.insert(messages.end(), good.begin() + at, good.end());
      const grpc::Status status = SendRawBytes(server_->NewChannel(), messages);
      EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT)
          << "garbage " << g << " at message " << at << ": " << status.error_message();
      EXPECT_THAT(status.error_message(), HasSubstr("request message " + std::to_string(at) +
                                                    " did not parse as a RefineRequest"))
          << "garbage " << g;
    }
  }
  // And random bytes, seeded so that a failure can be replayed.
  const uint32_t seed = 20240611;
  std::mt19937 rng(seed);
  for (int round = 0; round < 50; ++round) {
    std::string bytes(1 + rng() % 64, '\0');
    for (char& b : bytes) b = static_cast<char>(rng());
    const grpc::Status status = SendRawBytes(server_->NewChannel(), {bytes});
    EXPECT_FALSE(status.ok()) << "seed " << seed << " round " << round;
  }
  ExpectServesAGoodRequest();
}

}  // namespace
}  // namespace tetrefine::hardening
