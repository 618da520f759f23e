#include "tests/support/malformed_requests.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <map>
#include <utility>
#include <vector>

#include "core/five_tet_cell.h"
#include "gtest/gtest.h"
#include "tests/support/geometry.h"
#include "wire/request_writer.h"

namespace tetrefine::testing {
namespace {

using Requests = RefineRequests;
using Kind = v1::RefineRequest::KindCase;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

Requests Write(const Volume& volume, const Mesh& mesh, wire::RequestOptions options = {}) {
  const RefineOptions good = SmallRefineOptions();
  options.refine.epsilon = good.epsilon;
  options.refine.max_iterations = good.max_iterations;
  Requests requests;
  wire::WriteRequest(options, volume, mesh, 200, [&](const v1::RefineRequest& r) {
    requests.push_back(r);
    return true;
  });
  return requests;
}
Requests ValidRequests() { return GoodRequests(); }
// The good stream as a client that sends vertex values would write it: has_values set and the
// 27 values in two value chunks before end_of_input (the request writer sends none).
Requests WithValues() {
  Requests r = Write(SmallVolume(), SmallMesh());
  for (v1::RefineRequest& m : r) {
    if (m.has_mesh_header()) m.mutable_mesh_header()->set_has_values(true);
  }
  for (int start : {0, 25}) {
    v1::RefineRequest values;
    values.mutable_value_chunk()->set_start_index(start);
    for (int i = start; i < std::min(start + 25, 27); ++i) {
      values.mutable_value_chunk()->add_values(0.1 * i);
    }
    r.insert(r.end() - 1, values);
  }
  return r;
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
// vertex just off it, oriented positively: that face then lies in three tets.
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
    // Off the face along its normal, so the new tet is never flat whichever way the cells of
    // the mesh are split.
    const Vec3& a = mesh.points[face[0]];
    const Vec3& b = mesh.points[face[1]];
    const Vec3& c = mesh.points[face[2]];
    const Vec3 u{b[0] - a[0], b[1] - a[1], b[2] - a[2]};
    const Vec3 v{c[0] - a[0], c[1] - a[1], c[2] - a[2]};
    const Vec3 normal{u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2],
                      u[0] * v[1] - u[1] * v[0]};
    const double length =
        std::sqrt(normal[0] * normal[0] + normal[1] * normal[1] + normal[2] * normal[2]);
    for (int axis = 0; axis < 3; ++axis) centre[axis] += 0.3 * normal[axis] / length;
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

// SmallMesh with one tet split in two at the midpoint of an edge another tet shares, that tet
// left whole: a hanging node (vertex 27) that the face check alone lets through.
Mesh HangingNodeMesh() {
  Mesh mesh = SmallMesh();
  auto tets_on_edge = [&](uint32_t u, uint32_t v) {
    return std::count_if(mesh.tets.begin(), mesh.tets.end(), [&](const Tet& t) {
      return std::find(t.begin(), t.end(), u) != t.end() &&
             std::find(t.begin(), t.end(), v) != t.end();
    });
  };
  size_t t = 0;
  while (tets_on_edge(mesh.tets[t][0], mesh.tets[t][1]) < 2) ++t;
  const Tet tet = mesh.tets[t];
  const Vec3& a = mesh.points[tet[0]];
  const Vec3& b = mesh.points[tet[1]];
  const auto mid = static_cast<uint32_t>(mesh.points.size());
  mesh.points.push_back({0.5 * (a[0] + b[0]), 0.5 * (a[1] + b[1]), 0.5 * (a[2] + b[2])});
  mesh.tets[t] = {mid, tet[1], tet[2], tet[3]};
  mesh.tets.push_back({tet[0], mid, tet[2], tet[3]});
  return mesh;
}

// SmallMesh with its first cell split the other way: the three square faces that cell shares
// with its neighbours are cut by crossing diagonals. No vertex hangs and every boundary edge is
// used twice; only the fold check sees it.
Mesh CrossingDiagonalsMesh() {
  Mesh mesh = SmallMesh();
  // Cell (0, 0, 0) of the 3 x 3 x 3 points, x fastest, as FiveTetMesh numbers them.
  std::array<uint32_t, 8> corner;
  for (int b = 0; b < 8; ++b) {
    corner[b] = static_cast<uint32_t>((b & 1) + 3 * ((b >> 1) & 1) + 9 * ((b >> 2) & 1));
  }
  std::vector<Tet> odd;
  AppendFiveTetCell(corner, /*even=*/false, mesh.points, &odd);
  std::copy(odd.begin(), odd.end(), mesh.tets.begin());
  return mesh;
}

// CrossingDiagonalsMesh with the grid's centre vertex (13), a corner of the three crossed
// squares, moved off their planes: the squares twist, and the two sides of one bulge into each
// other, which only the shell check sees (the faces no longer fold in one plane).
Mesh TwistedCrossingDiagonalsMesh() {
  Mesh mesh = CrossingDiagonalsMesh();
  Vec3& centre = mesh.points[13];
  centre = {centre[0] + 0.4, centre[1] + 0.3, centre[2] + 0.2};
  return mesh;
}

// SmallMesh with one more tet of its own vertices lying inside it: no face, edge or vertex
// shared, both boundaries closed, so only the overlap check (check 5) sees it.
Mesh TetInsideMesh() {
  Mesh mesh = SmallMesh();
  const auto base = static_cast<uint32_t>(mesh.points.size());
  for (const Vec3& p :
       {Vec3{3.3, 3.7, 4.1}, Vec3{3.9, 3.7, 4.1}, Vec3{3.3, 4.3, 4.1}, Vec3{3.3, 3.7, 4.7}}) {
    mesh.points.push_back(p);
  }
  mesh.tets.push_back({base, base + 1, base + 2, base + 3});
  return mesh;
}

// A case built by editing the good stream.
MalformedRequest Edit(std::string name, std::function<void(Requests&)> edit,
                      std::vector<std::string> parts,
                      grpc::StatusCode code = grpc::StatusCode::INVALID_ARGUMENT) {
  return {std::move(name),
          [edit] {
            Requests r = ValidRequests();
            edit(r);
            return r;
          },
          std::move(parts), code};
}

// The same, written as a table of edits.
struct Malformation {
  std::string name;
  std::function<void(Requests&)> mutate;
  std::vector<std::string> message_parts;
  grpc::StatusCode code = grpc::StatusCode::INVALID_ARGUMENT;
};

std::vector<MalformedRequest> Edits(std::vector<Malformation> table) {
  std::vector<MalformedRequest> out;
  for (Malformation& m : table) {
    out.push_back(Edit(std::move(m.name), std::move(m.mutate), std::move(m.message_parts), m.code));
  }
  return out;
}

}  // namespace

const Volume& SmallVolume() {
  static const Volume* volume = new Volume(TestVolume({10, 10, 10}));
  return *volume;
}

const Mesh& SmallMesh() {
  static const Mesh* mesh = new Mesh(FiveTetMesh({1.0, 1.0, 1.0}, {8.0, 8.0, 8.0}, {2, 2, 2}));
  return *mesh;
}

RefineOptions SmallRefineOptions() {
  RefineOptions options;
  options.epsilon = 0.05;
  options.max_iterations = 2;
  return options;
}

Requests GoodRequests() { return Write(SmallVolume(), SmallMesh()); }

void PrintTo(const MalformedRequest& c, std::ostream* os) { *os << c.name; }

std::vector<MalformedRequest> MalformedRequests() {
  std::vector<MalformedRequest> cases = Edits({
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
      {"DirectionWrongCount",
       [](Requests& r) {
         for (double d : {1.0, 0.0, 0.0, 1.0}) VolumeHeader(r).add_direction(d);
       },
       {"volume_header.direction", "0 (identity) or 9 values", "got 4"}},
      {"DirectionSingular",
       [](Requests& r) {
         // Columns 0 and 1 both along world x.
         for (double d : {1.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0}) {
           VolumeHeader(r).add_direction(d);
         }
       },
       {"volume_header.direction", "singular"}},
      {"DirectionNaN",
       [](Requests& r) {
         for (double d : {1.0, 0.0, 0.0, 0.0, kNaN, 0.0, 0.0, 0.0, 1.0}) {
           VolumeHeader(r).add_direction(d);
         }
       },
       {"volume_header.direction[4]", "nan"}},
      {"DirectionWithLengths",
       [](Requests& r) {
         // An affine's 3x3 part (voxel sizes 1, 1, 2.5) sent as the direction.
         for (double d : {1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 2.5}) {
           VolumeHeader(r).add_direction(d);
         }
       },
       {"volume_header.direction: column 2 has length 2.5", "unit vectors",
        "volume_header.spacing"}},
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
       {"value_chunk not accepted", "samples every vertex value"}},
      {"ValuesAnnounced",
       [](Requests& r) {
         MeshHeader(r).set_has_values(true);
         v1::RefineRequest values;
         for (int i = 0; i < 27; ++i) values.mutable_value_chunk()->add_values(i == 3 ? kNaN : 1.0);
         r.insert(r.end() - 1, values);
       },
       {"mesh_header.has_values: must be false"}},
      {"LabelsNotAnnounced",
       [](Requests& r) {
         v1::RefineRequest labels;
         labels.mutable_tet_label_chunk()->add_labels(3);
         r.insert(r.end() - 1, labels);
       },
       {"tet_label_chunk without mesh_header.has_labels"}},
      {"LabelsMissing",
       [](Requests& r) {
         MeshHeader(r).set_has_labels(true);
         v1::RefineRequest labels;
         for (int i = 0; i < 39; ++i) labels.mutable_tet_label_chunk()->add_labels(i);
         r.insert(r.end() - 1, labels);
       },
       {"tet_label_chunk: received 39 labels, mesh_header.tet_count = 40"}},
      {"LabelsRunPastTheTets",
       [](Requests& r) {
         MeshHeader(r).set_has_labels(true);
         v1::RefineRequest labels;
         for (int i = 0; i < 41; ++i) labels.mutable_tet_label_chunk()->add_labels(i);
         r.insert(r.end() - 1, labels);
       },
       {"tet_label_chunk.labels: 41 labels at start_index 0 run past mesh_header.tet_count = 40"}},
      {"LabelChunkGap",
       [](Requests& r) {
         MeshHeader(r).set_has_labels(true);
         v1::RefineRequest labels;
         labels.mutable_tet_label_chunk()->set_start_index(5);
         labels.mutable_tet_label_chunk()->add_labels(1);
         r.insert(r.end() - 1, labels);
       },
       {"tet_label_chunk.start_index: expected 0", "got 5"}},
      {"UnknownScheme",
       [](Requests& r) { r[0].mutable_options()->set_scheme(static_cast<v1::RefineScheme>(7)); },
       {"options.scheme: unknown value 7"}},
      {"CertifyWithoutLattice",
       [](Requests& r) {
         r[0].mutable_options()->set_certify(true);
         r[0].mutable_options()->set_lattice_n(0);
       },
       {"options.lattice_n", "certify needs a lattice"}},
      {"TetChunkAfterEndOfInput",
       [](Requests& r) { r.push_back(r[Find(r, Kind::kTetChunk)]); },
       {"expected nothing after end_of_input, got tet_chunk"}},
      {"DimsAboveTheCoreBound",
       [](Requests& r) { VolumeHeader(r).mutable_dims()->set_x(1 << 21); },
       {"volume_header.dims.x: must be in [2, 1048576], got 2097152"}},
      {"NormCoeffTiny",
       [](Requests& r) { Options(r).set_norm_coeff(1e-310); },
       {"options.norm_coeff: must be a normal number"}},
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
  });
  const auto kExhausted = grpc::StatusCode::RESOURCE_EXHAUSTED;
  std::vector<MalformedRequest> more = {
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
      // Client vertex values are refused where they are announced (the server samples every
      // vertex; tetrefine.proto, MeshHeader.has_values).
      {"ValuesSent",
       [] { return WithValues(); },
       {"mesh_header.has_values: must be false", "samples every vertex value from the volume"}},
      Edit("VolumeChunkDuplicated",
           [](Requests& r) { Duplicate(r, Find(r, Kind::kVolumeChunk, 1)); },
           {"volume_chunk.offset: expected 400", "got 200"}),
      Edit("VertexChunkDuplicated",
           [](Requests& r) { Duplicate(r, Find(r, Kind::kVertexChunk, 0)); },
           {"vertex_chunk.start_index: expected 8", "got 0"}),
      Edit("TetChunkDuplicated", [](Requests& r) { Duplicate(r, FindLast(r, Kind::kTetChunk)); },
           {"tet_chunk.start_index: expected 40", "got 36"}),
      Edit("VolumeHeaderTwice", [](Requests& r) { Duplicate(r, Find(r, Kind::kVolumeHeader)); },
           {"expected volume_chunk", "got volume_header"}),
      Edit("MeshHeaderTwice", [](Requests& r) { Duplicate(r, Find(r, Kind::kMeshHeader)); },
           {"expected vertex_chunk, tet_chunk or end_of_input", "got mesh_header"}),
      Edit("TetChunkMissing", [](Requests& r) { r.erase(r.begin() + Find(r, Kind::kTetChunk, 1)); },
           {"tet_chunk.start_index: expected 12", "got 24"}),
      {"ValuesAnnouncedNotSent",
       [] {
         Requests r = ValidRequests();
         MeshHeader(r).set_has_values(true);
         return r;
       },
       {"mesh_header.has_values: must be false"}},
      {"ValueChunkWithoutHeaderFlag",
       [] {
         Requests r = WithValues();
         MeshHeader(r).set_has_values(false);
         return r;
       },
       {"request message", "value_chunk not accepted"}},
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
           {"volume_header.dims.z: must be in [2, 1048576], got 2147483649"}),
      // A small slab of a grid too large for the core's index arithmetic: refused at the header,
      // before the slab's data is sent (the core would refuse it only once the data is in).
      Edit("SlabOfAGridAboveTwoToThe20",
           [](Requests& r) { VolumeHeader(r).mutable_dims()->set_y((int64_t{1} << 20) + 1); },
           {"volume_header.dims.y: must be in [2, 1048576], got 1048577"}),
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
      // Stream contract: nothing may follow end_of_input.
      Edit("MessageAfterEndOfInput",
           [](Requests& r) { r.push_back(r[Find(r, Kind::kTetChunk, 0)]); },
           {"expected nothing after end_of_input, got tet_chunk"}),
      Edit("EndOfInputTwice", [](Requests& r) { r.push_back(r.back()); },
           {"expected nothing after end_of_input, got end_of_input"}),
      Edit("OptionsAfterEndOfInput", [](Requests& r) { r.push_back(r.front()); },
           {"expected nothing after end_of_input, got options"}),
      // Normalisations that would turn every error into inf.
      Edit("NormCoeffSubnormal", [](Requests& r) { Options(r).set_norm_coeff(5e-324); },
           {"options.norm_coeff: must be a normal number", "got 4.94066e-324"}),
      Edit("NormCoeffTooSmallForTheRange", [](Requests& r) { Options(r).set_norm_coeff(1e-300); },
           {"options.norm_coeff: 1e-300 is too small for the volume's value range",
            "must be at least range / 1e+280"}),
      // Per-call work caps, answered with the options.
      Edit(
          "MaxIterationsAboveTheCap", [](Requests& r) { Options(r).set_max_iterations(101); },
          {"options.max_iterations: 101 exceeds this server's limit of 100 iterations"},
          kExhausted),
      Edit(
          "LatticeNAboveTheCap", [](Requests& r) { Options(r).set_lattice_n(17); },
          {"options.lattice_n: 17 exceeds this server's limit of 16 (--max_lattice_n)"},
          kExhausted),
      Edit(
          "LatticeOfEveryTetUpToTheBudget",
          [](Requests& r) {
            Options(r).set_lattice_n(8);
            Options(r).set_lattice_max_tets(0);
          },
          {"options.lattice_n = 8 (165 points a tet) on up to 50000000 tets",
           "every tet, up to max_tets", "above this server's limit of 200000000",
           "--max_lattice_points"},
          kExhausted),
      Edit("SpacingInfinite", [](Requests& r) { VolumeHeader(r).mutable_spacing()->set_y(kInf); },
           {"volume_header.spacing.y: must be finite and > 0", "got inf"}),
      Edit("SpacingSubnormal",
           [](Requests& r) { VolumeHeader(r).mutable_spacing()->set_x(1e-310); },
           {"volume_header.spacing.x: must be finite and > 0 (at least 2.22507e-308), got 1e-310"}),
      Edit("GridBeyondFloat64",
           [](Requests& r) {
             VolumeHeader(r).mutable_origin()->set_z(1e308);
             VolumeHeader(r).mutable_spacing()->set_z(1e308);
           },
           {"volume grid: its far corner", "overflows float64"}),
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
           {"mesh.tets[0] and mesh.tets[1] are the same tet", "an element listed twice"}),
      {"FaceInThreeTets",
       [] { return Write(SmallVolume(), NonManifoldMesh()); },
       {"is shared by 3 tets", "a face may belong to at most two"}},
      {"HangingNode",
       [] { return Write(SmallVolume(), HangingNodeMesh()); },
       {"mesh is not conformal: vertex 27 at", "a hanging node"}},
      {"CrossingDiagonals",
       [] { return Write(SmallVolume(), CrossingDiagonalsMesh()); },
       {"mesh is not conformal: boundary faces (", "crossing diagonals"}},
      {"TwistedCrossingDiagonals",
       [] { return Write(SmallVolume(), TwistedCrossingDiagonalsMesh()); },
       {"mesh is not conformal: boundary faces on vertices (", "so two tets overlap"}},
      {"TetInsideTheMesh",
       [] { return Write(SmallVolume(), TetInsideMesh()); },
       {"mesh is not conformal: mesh.tets[",
        "] and mesh.tets[40] overlap (their interiors "
        "intersect"}},
      // A slab and a mesh that reaches beyond it.
      {"MeshOutsideItsSlab",
       [] {
         return Write(TestSlab({10, 10, 10}, {0, 0, 0}, {10, 10, 5}), SmallMesh());
       },
       {"lies outside the volume's sampled box", "[0, 4]"}},
      {"MeshOutsideItsSlabWhenClamping",
       [] {
         wire::RequestOptions options;
         options.refine.outside = OutsidePolicy::kClamp;
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
  cases.insert(cases.end(), std::make_move_iterator(more.begin()),
               std::make_move_iterator(more.end()));
  return cases;
}

}  // namespace tetrefine::testing
