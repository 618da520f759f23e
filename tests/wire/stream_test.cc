// Direct tests of the streamed parts of the wire layer: a request written by WriteRequest is read
// back by RequestReader unchanged whatever the chunk size, a response written by ResponseWriter
// is read back by ResponseReader unchanged, and a reader refuses a broken stream naming the field
// and the index.

#include <cmath>
#include <cstddef>
#include <string>
#include <vector>

#include "core/refine.h"
#include "gmock/gmock.h"
#include "gtest/gtest.h"
#include "tests/support/geometry.h"
#include "tests/support/result_compare.h"
#include "wire/request_reader.h"
#include "wire/request_writer.h"
#include "wire/response_reader.h"
#include "wire/response_writer.h"

namespace tetrefine::wire {
namespace {

using ::testing::HasSubstr;
using ::testing::StartsWith;
using tetrefine::testing::ExpectSameMesh;
using tetrefine::testing::ExpectSameResult;
using tetrefine::testing::FiveTetMesh;
using tetrefine::testing::TestSlab;

std::vector<v1::RefineRequest> Requests(const RequestOptions& options, const Volume& volume,
                                        const Mesh& mesh, size_t chunk_bytes) {
  std::vector<v1::RefineRequest> out;
  EXPECT_TRUE(WriteRequest(options, volume, mesh, chunk_bytes, [&](const v1::RefineRequest& r) {
    out.push_back(r);
    return true;
  }));
  return out;
}

// Feeds `requests` to a reader; the first error, or OK once complete.
absl::Status Read(const std::vector<v1::RefineRequest>& requests, RequestReader& reader) {
  for (const v1::RefineRequest& r : requests) {
    if (absl::Status s = reader.Add(r); !s.ok()) return s;
  }
  return reader.complete() ? absl::OkStatus() : reader.IncompleteError();
}

Mesh TestMesh(bool with_values) {
  Mesh mesh = FiveTetMesh({1.0, 1.0, 1.0}, {8.0, 8.0, 6.0}, {3, 2, 2});
  if (with_values) {
    for (const Vec3& p : mesh.points) mesh.values.push_back(p[0] - 2.0 * p[1] + 0.5 * p[2]);
  }
  return mesh;
}

TEST(WireRequestStream, RoundTripsAtEveryChunkSizeAndVoxelType) {
  RequestOptions options;
  options.refine.epsilon = 0.07;
  options.SetMaxTets(5000);
  for (VoxelType type : {VoxelType::kUint8, VoxelType::kInt16, VoxelType::kUint16,
                         VoxelType::kInt32, VoxelType::kFloat32, VoxelType::kFloat64}) {
    const Volume volume = TestSlab({10, 9, 8}, {0, 1, 0}, {10, 9, 7}, type);
    for (bool with_values : {false, true}) {
      const Mesh mesh = TestMesh(with_values);
      for (size_t chunk_bytes : {size_t{1}, size_t{7}, size_t{100}, kDefaultChunkBytes}) {
        SCOPED_TRACE(std::string(VoxelTypeName(type)) + " chunk " + std::to_string(chunk_bytes));
        RequestReader reader(ServiceLimits{});
        ASSERT_TRUE(Read(Requests(options, volume, mesh, chunk_bytes), reader).ok());
        EXPECT_EQ(reader.tets_declared(), static_cast<int64_t>(mesh.tets.size()));
        const RefineInput input = reader.Take();
        EXPECT_EQ(input.options.refine.epsilon, 0.07);
        EXPECT_EQ(input.options.refine.max_tets, 5000);
        EXPECT_EQ(input.volume.grid().dims, volume.grid().dims);
        EXPECT_EQ(input.volume.lo(), volume.lo());
        EXPECT_EQ(input.volume.hi(), volume.hi());
        EXPECT_EQ(input.volume.type(), type);
        EXPECT_EQ(input.volume.data(), volume.data());
        // Vertex values are never sent: the server samples the volume.
        Mesh sent = mesh;
        sent.values.clear();
        ExpectSameMesh(sent, input.mesh);
      }
    }
  }
}

// The request stream of TestMesh with one message changed by `edit`; the reader's error.
template <typename Edit>
absl::Status ReadEdited(Edit edit, const ServiceLimits& limits = {}) {
  std::vector<v1::RefineRequest> requests =
      Requests(RequestOptions{}, TestSlab({10, 10, 10}, {0, 0, 0}, {10, 10, 10}),
               TestMesh(/*with_values=*/true), /*chunk_bytes=*/64);
  edit(requests);
  RequestReader reader(limits);
  return Read(requests, reader);
}

// The index of the first request of `kind` (after `from`).
size_t Find(const std::vector<v1::RefineRequest>& requests, v1::RefineRequest::KindCase kind,
            size_t from = 0) {
  for (size_t i = from; i < requests.size(); ++i) {
    if (requests[i].kind_case() == kind) return i;
  }
  ADD_FAILURE() << "no request of kind " << kind;
  return 0;
}

// An oblique direction travels as 9 doubles and comes back to the bit; the identity travels as
// nothing, so axis-aligned requests are the bytes they always were.
TEST(WireRequestStream, DirectionRoundTripsAndTheIdentityIsNotSent) {
  const Volume aligned = TestSlab({10, 9, 8}, {0, 1, 0}, {10, 9, 7});
  const Mesh mesh = TestMesh(false);
  std::vector<v1::RefineRequest> requests = Requests(RequestOptions{}, aligned, mesh, 100);
  EXPECT_EQ(
      requests[Find(requests, v1::RefineRequest::kVolumeHeader)].volume_header().direction_size(),
      0);
  GridGeometry g = aligned.grid();
  const double c = std::cos(0.4), s = std::sin(0.4);
  g.direction = {c, 0.0, s, 0.0, 1.0, 0.0, -s, 0.0, c};
  g.origin = {3.0, -2.0, 1.0};
  absl::StatusOr<Volume> oblique =
      Volume::Create(g, aligned.lo(), aligned.hi(), aligned.type(), aligned.data());
  ASSERT_TRUE(oblique.ok()) << oblique.status();
  requests = Requests(RequestOptions{}, *oblique, mesh, 100);
  const v1::VolumeHeader& header =
      requests[Find(requests, v1::RefineRequest::kVolumeHeader)].volume_header();
  ASSERT_EQ(header.direction_size(), 9);
  for (int i = 0; i < 9; ++i) EXPECT_EQ(header.direction(i), g.direction[i]) << i;
  RequestReader reader(ServiceLimits{});
  ASSERT_TRUE(Read(requests, reader).ok());
  const RefineInput input = reader.Take();
  EXPECT_EQ(input.volume.grid().direction, g.direction);
  EXPECT_EQ(input.volume.grid().origin, g.origin);
  EXPECT_FALSE(input.volume.axis_aligned());
  const Vec3 p = WorldOfIndex(g, {2.5, 3.25, 4.0});
  EXPECT_EQ(input.volume.Sample(p), oblique->Sample(p));
}

TEST(WireRequestStream, TetIndexOutOfRangeNamesTetAndCorner) {
  const absl::Status s = ReadEdited([](std::vector<v1::RefineRequest>& r) {
    // The second tet chunk starts at tet 4 (64 bytes = 4 tets); its tet 5 corner 2.
    const size_t first = Find(r, v1::RefineRequest::kTetChunk);
    r[first + 1].mutable_tet_chunk()->set_indices(4 + 2, 1'000'000);
  });
  EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(std::string(s.message()),
              StartsWith("tet_chunk.indices: tet 5 corner 2 is vertex 1000000"));
}

TEST(WireRequestStream, NonFiniteCoordinateNamesVertexAndAxis) {
  const absl::Status s = ReadEdited([](std::vector<v1::RefineRequest>& r) {
    // 64 bytes = 2 vertices a chunk: the third chunk holds vertices 4 and 5.
    const size_t first = Find(r, v1::RefineRequest::kVertexChunk);
    r[first + 2].mutable_vertex_chunk()->set_coordinates(3 + 1, std::nan(""));
  });
  EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(std::string(s.message()),
              StartsWith("vertex_chunk.coordinates: vertex 5 has a non-finite y"));
}

TEST(WireRequestStream, VertexValuesAreRefusedWhereTheyAreAnnounced) {
  const absl::Status s = ReadEdited([](std::vector<v1::RefineRequest>& r) {
    // The writer drops TestMesh's values; a client of its own announces them.
    for (const v1::RefineRequest& m : r) {
      EXPECT_FALSE(m.has_value_chunk());
      EXPECT_FALSE(m.has_mesh_header() && m.mesh_header().has_values());
    }
    r[Find(r, v1::RefineRequest::kMeshHeader)].mutable_mesh_header()->set_has_values(true);
  });
  EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(std::string(s.message()), StartsWith("mesh_header.has_values: must be false"));
}

TEST(WireRequestStream, MissingChunkNamesTheExpectedOffset) {
  const absl::Status s = ReadEdited([](std::vector<v1::RefineRequest>& r) {
    r.erase(r.begin() + static_cast<ptrdiff_t>(Find(r, v1::RefineRequest::kVolumeChunk)) + 1);
  });
  EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(std::string(s.message()), StartsWith("volume_chunk.offset: expected 64"));
}

TEST(WireRequestStream, WrongTotalBytesNamesTheField) {
  const absl::Status s = ReadEdited([](std::vector<v1::RefineRequest>& r) {
    r[Find(r, v1::RefineRequest::kVolumeHeader)].mutable_volume_header()->set_total_bytes(7);
  });
  EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(std::string(s.message()), StartsWith("volume_header.total_bytes: expected 8000"));
}

TEST(WireRequestStream, BadDimsAndSlabNameTheAxis) {
  absl::Status s = ReadEdited([](std::vector<v1::RefineRequest>& r) {
    r[Find(r, v1::RefineRequest::kVolumeHeader)].mutable_volume_header()->mutable_dims()->set_y(1);
  });
  EXPECT_THAT(std::string(s.message()), StartsWith("volume_header.dims.y: must be in [2, "));
  s = ReadEdited([](std::vector<v1::RefineRequest>& r) {
    r[Find(r, v1::RefineRequest::kVolumeHeader)].mutable_volume_header()->mutable_slab_hi()->set_z(
        11);
  });
  EXPECT_THAT(std::string(s.message()),
              StartsWith("volume_header.slab_hi.z: must be in (0, 10], got 11"));
}

TEST(WireRequestStream, OutOfOrderMessagesNameTheIndexAndWhatWasExpected) {
  const absl::Status s = ReadEdited([](std::vector<v1::RefineRequest>& r) {
    std::swap(r[0], r[1]);  // volume_header before options
  });
  EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(std::string(s.message()),
              StartsWith("request message 0: expected options (it must come first), "
                         "got volume_header"));
}

TEST(WireRequestStream, TruncatedStreamSaysWhatIsMissing) {
  const absl::Status s = ReadEdited([](std::vector<v1::RefineRequest>& r) { r.pop_back(); });
  EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(std::string(s.message()), StartsWith("end_of_input: missing"));
}

TEST(WireRequestStream, LimitsAreCheckedOnDeclaredSizes) {
  ServiceLimits limits;
  limits.max_voxels = 999;  // the volume has 1000
  absl::Status s = ReadEdited([](std::vector<v1::RefineRequest>&) {}, limits);
  EXPECT_EQ(s.code(), absl::StatusCode::kResourceExhausted);
  EXPECT_THAT(std::string(s.message()), StartsWith("volume_header: the slab"));
  EXPECT_THAT(std::string(s.message()), HasSubstr("999 voxels"));

  limits = ServiceLimits{};
  limits.max_input_tets = 10;  // the mesh has 60
  s = ReadEdited([](std::vector<v1::RefineRequest>&) {}, limits);
  EXPECT_EQ(s.code(), absl::StatusCode::kResourceExhausted);
  EXPECT_THAT(std::string(s.message()),
              StartsWith("mesh_header.tet_count: 60 exceeds this server's limit of 10"));

  // A declared size is refused before any data arrives: the absurd count alone is enough.
  s = ReadEdited([](std::vector<v1::RefineRequest>& r) {
    r[Find(r, v1::RefineRequest::kMeshHeader)].mutable_mesh_header()->set_vertex_count(int64_t{1}
                                                                                       << 60);
  });
  EXPECT_EQ(s.code(), absl::StatusCode::kResourceExhausted);
  EXPECT_THAT(std::string(s.message()), StartsWith("mesh_header.vertex_count: "));
}

// A real result (a few iterations of core Refine) through the response writer and reader.
RefineResult SmallResult() {
  const Volume volume = testing::TestVolume({10, 10, 10});
  RefineOptions options;
  options.epsilon = 0.02;
  options.max_iterations = 3;
  absl::StatusOr<RefineResult> result =
      Refine(volume, FiveTetMesh({1.0, 1.0, 1.0}, {8.0, 8.0, 8.0}, {2, 2, 2}), options);
  EXPECT_TRUE(result.ok()) << result.status();
  return *std::move(result);
}

TEST(WireResponseStream, RoundTripsAtTheSmallestAndDefaultChunk) {
  const RefineResult result = SmallResult();
  ASSERT_GE(result.iterations.size(), 2u);
  for (size_t chunk_bytes : {size_t{1}, size_t{0}}) {  // clamped to 256; 0: the default
    std::vector<v1::RefineResponse> responses;
    ResponseWriter writer(chunk_bytes, [&](const v1::RefineResponse& r) {
      responses.push_back(r);
      return true;
    });
    for (const IterationStats& s : result.iterations) {
      ASSERT_TRUE(writer.WriteIterationStats(s));
      ASSERT_TRUE(writer.WriteMesh(s.iteration, false, result.mesh, {}, {}));
    }
    ASSERT_TRUE(writer.WriteMesh(static_cast<int>(result.iterations.size()), true, result.mesh,
                                 result.tet_iteration, result.tet_quality));
    const ServiceSummary service{.max_tets = 123, .input_seconds = 0.25, .total_seconds = 1.5};
    ASSERT_TRUE(writer.WriteSummary(result, service, 40));

    int stats_seen = 0, meshes_seen = 0;
    ResponseReader reader([&](const IterationStats&) { ++stats_seen; },
                          [&](int, const Mesh& mesh) {
                            ++meshes_seen;
                            ExpectSameMesh(result.mesh, mesh);
                          },
                          /*expect_final_mesh=*/true);
    for (const v1::RefineResponse& r : responses) ASSERT_TRUE(reader.Add(r).ok());
    ASSERT_TRUE(reader.complete());
    const RefineReply reply = reader.Take();
    EXPECT_EQ(stats_seen, static_cast<int>(result.iterations.size()));
    EXPECT_EQ(meshes_seen, static_cast<int>(result.iterations.size()));
    ExpectSameResult(result, reply.result);
    EXPECT_EQ(reply.service.max_tets, 123);
    EXPECT_EQ(reply.service.total_seconds, 1.5);
  }
}

// Labels sent with the mesh reach the reader; labels and parents of a result (certified, the
// longest-edge scheme's statistics) come back through the response stream.
TEST(WireStreams, LabelsParentsAndCertifiedResultsRoundTrip) {
  Mesh mesh = TestMesh(/*with_values=*/false);
  for (size_t t = 0; t < mesh.tets.size(); ++t) mesh.labels.push_back(static_cast<int>(t) - 5);
  RequestOptions options;
  options.refine.scheme = RefineScheme::kLongestEdge;
  options.refine.certify = true;
  options.refine.track_parents = true;
  const Volume volume = TestSlab({10, 10, 10}, {0, 0, 0}, {10, 10, 10});
  for (size_t chunk_bytes : {size_t{1}, kDefaultChunkBytes}) {
    RequestReader reader(ServiceLimits{});
    ASSERT_TRUE(Read(Requests(options, volume, mesh, chunk_bytes), reader).ok());
    const RefineInput input = reader.Take();
    EXPECT_EQ(input.mesh.labels, mesh.labels);
    EXPECT_EQ(input.options.refine.scheme, RefineScheme::kLongestEdge);
    EXPECT_TRUE(input.options.refine.certify);
    EXPECT_TRUE(input.options.refine.track_parents);
  }

  RefineOptions core = options.refine;
  core.epsilon = 0.05;
  core.max_iterations = 6;
  absl::StatusOr<RefineResult> result = Refine(volume, mesh, core);
  ASSERT_TRUE(result.ok()) << result.status();
  ASSERT_EQ(result->mesh.labels.size(), result->mesh.tets.size());
  ASSERT_EQ(result->tet_parent.size(), result->mesh.tets.size());
  std::vector<v1::RefineResponse> responses;
  ResponseWriter writer(256, [&](const v1::RefineResponse& r) {
    responses.push_back(r);
    return true;
  });
  for (const IterationStats& s : result->iterations) ASSERT_TRUE(writer.WriteIterationStats(s));
  ASSERT_TRUE(writer.WriteMesh(static_cast<int>(result->iterations.size()), true, result->mesh,
                               result->tet_iteration, result->tet_quality, result->tet_parent));
  ASSERT_TRUE(writer.WriteSummary(*result, {}, static_cast<int64_t>(mesh.tets.size())));
  ResponseReader response_reader(nullptr, nullptr, /*expect_final_mesh=*/true);
  for (const v1::RefineResponse& r : responses) ASSERT_TRUE(response_reader.Add(r).ok());
  ASSERT_TRUE(response_reader.complete());
  ExpectSameResult(*result, response_reader.Take().result);
}

// A label chunk's labels take what LabelWireBytes says, so its message stays within the chunk
// size (plus the chunk's own few bytes of framing) for negative and large labels too: sized at 4
// bytes a label, -1 labels took 10 each and a server's --max_message_bytes refused them.
TEST(WireStreams, LabelChunksStayWithinTheChunkSizeWhateverTheLabels) {
  EXPECT_EQ(LabelWireBytes({}), 1u);
  EXPECT_EQ(LabelWireBytes({0, 127}), 1u);
  EXPECT_EQ(LabelWireBytes({128}), 2u);
  EXPECT_EQ(LabelWireBytes({(1 << 28) - 1}), 4u);
  EXPECT_EQ(LabelWireBytes({1 << 28, 3}), 5u);
  EXPECT_EQ(LabelWireBytes({2147483647}), 5u);
  EXPECT_EQ(LabelWireBytes({5, -1}), 10u);
  const Mesh base = TestMesh(/*with_values=*/false);
  const Volume volume = TestSlab({10, 10, 10}, {0, 0, 0}, {10, 10, 10});
  constexpr size_t kChunk = 256;
  constexpr size_t kFraming = 16;  // oneof tag, length, start_index, the packed field's header
  for (const int32_t label : {3, 1 << 29, -1, -2147483647 - 1}) {
    SCOPED_TRACE(label);
    Mesh mesh = base;
    mesh.labels.assign(mesh.tets.size(), label);
    size_t label_chunks = 0;
    for (const v1::RefineRequest& r : Requests(RequestOptions{}, volume, mesh, kChunk)) {
      if (!r.has_tet_label_chunk()) continue;
      ++label_chunks;
      EXPECT_LE(r.ByteSizeLong(), kChunk + kFraming);
    }
    EXPECT_GE(label_chunks, 1u);
    size_t response_label_chunks = 0;
    ResponseWriter writer(kChunk, [&](const v1::RefineResponse& r) {
      if (r.has_tet_label_chunk()) {
        ++response_label_chunks;
        EXPECT_LE(r.ByteSizeLong(), kChunk + kFraming);
      }
      return true;
    });
    ASSERT_TRUE(writer.WriteMesh(1, true, mesh, {}, {}));
    EXPECT_GE(response_label_chunks, 1u);
  }
}

TEST(WireResponseStream, ReaderRefusesABrokenStreamNamingTheField) {
  const RefineResult result = SmallResult();
  std::vector<v1::RefineResponse> responses;
  ResponseWriter writer(256, [&](const v1::RefineResponse& r) {
    responses.push_back(r);
    return true;
  });
  ASSERT_TRUE(writer.WriteMesh(1, true, result.mesh, result.tet_iteration, result.tet_quality));
  ASSERT_TRUE(writer.WriteSummary(result, {}, 40));

  auto read = [](const std::vector<v1::RefineResponse>& stream) {
    ResponseReader reader(nullptr, nullptr, /*expect_final_mesh=*/true);
    for (const v1::RefineResponse& r : stream) {
      if (absl::Status s = reader.Add(r); !s.ok()) return s;
    }
    return absl::OkStatus();
  };
  std::vector<v1::RefineResponse> broken = responses;
  broken.erase(broken.begin() + 1);  // the first vertex chunk
  absl::Status s = read(broken);
  EXPECT_EQ(s.code(), absl::StatusCode::kInternal);
  EXPECT_THAT(std::string(s.message()), HasSubstr("vertex_chunk.start_index: expected 0"));

  broken = responses;
  for (v1::RefineResponse& r : broken) {
    if (r.has_tet_chunk()) {
      r.mutable_tet_chunk()->set_indices(0, 1u << 30);
      break;
    }
  }
  s = read(broken);
  EXPECT_EQ(s.code(), absl::StatusCode::kInternal);
  EXPECT_THAT(std::string(s.message()),
              HasSubstr("tet_chunk.indices: vertex 1073741824 out of range"));

  broken = {responses.back()};  // the summary alone
  s = read(broken);
  EXPECT_EQ(s.code(), absl::StatusCode::kInternal);
  EXPECT_THAT(std::string(s.message()), HasSubstr("summary before the final mesh"));
}

}  // namespace
}  // namespace tetrefine::wire
