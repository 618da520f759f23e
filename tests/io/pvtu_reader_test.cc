// Reading a .pvtu as one mesh: the pieces' shared vertices merged, arrays in piece order, and
// errors naming the index or the piece.
#include "client/io/pvtu_reader.h"

#include <string>
#include <vector>

#include "absl/strings/str_cat.h"
#include "client/io/mesh_io.h"
#include "client/io/pvtu_writer.h"
#include "gmock/gmock.h"
#include "gtest/gtest.h"
#include "tests/io/io_test_util.h"

namespace tetrefine::io::pvtu_reader_test {
namespace {

using iotest::RandomMesh;
using iotest::RandomMeshOptions;
using iotest::ScratchDir;
using iotest::WriteBytes;
using ::testing::HasSubstr;

// Tets [begin, end) of `whole` with their own vertex numbering (first use order) and arrays: a
// piece as a parallel writer makes it, a vertex shared with another piece in both.
MeshFile PieceOf(const MeshFile& whole, size_t begin, size_t end) {
  MeshFile piece;
  piece.label_name = whole.label_name;
  piece.frame = whole.frame;
  std::vector<int64_t> local(whole.mesh.points.size(), -1);
  for (size_t t = begin; t < end; ++t) {
    Tet tet;
    for (int c = 0; c < 4; ++c) {
      const uint32_t v = whole.mesh.tets[t][c];
      if (local[v] < 0) {
        local[v] = static_cast<int64_t>(piece.mesh.points.size());
        piece.mesh.points.push_back(whole.mesh.points[v]);
        if (!whole.mesh.values.empty()) piece.mesh.values.push_back(whole.mesh.values[v]);
      }
      tet[c] = static_cast<uint32_t>(local[v]);
    }
    piece.mesh.tets.push_back(tet);
    if (!whole.mesh.labels.empty()) piece.mesh.labels.push_back(whole.mesh.labels[t]);
    if (!whole.tet_iteration.empty()) piece.tet_iteration.push_back(whole.tet_iteration[t]);
    if (!whole.tet_quality.empty()) piece.tet_quality.push_back(whole.tet_quality[t]);
  }
  return piece;
}

std::vector<MeshFile> Split(const MeshFile& whole, int parts) {
  std::vector<MeshFile> pieces;
  const size_t n = whole.mesh.tets.size();
  for (int k = 0; k < parts; ++k)
    pieces.push_back(PieceOf(whole, n * k / parts, n * (k + 1) / parts));
  return pieces;
}

// `whole` with only the vertices its tets use, numbered in first-use order: what merging the
// pieces of Split gives back.
MeshFile Compacted(const MeshFile& whole) { return PieceOf(whole, 0, whole.mesh.tets.size()); }

TEST(IoPvtuReaderTest, PiecesMergeIntoTheWholeMesh) {
  ScratchDir dir;
  for (uint64_t seed = 1; seed <= 12; ++seed) {
    RandomMeshOptions options;
    options.labels = seed % 2 == 0;
    options.values = seed % 3 != 0;
    options.frame = seed % 4 == 0 ? MeshFrame::kLps : MeshFrame::kUntagged;
    const MeshFile whole = Compacted(RandomMesh(seed, options));
    for (int parts : {1, 2, 5}) {
      SCOPED_TRACE(absl::StrCat("seed ", seed, ", ", parts, " pieces"));
      const std::string path = dir.File(absl::StrCat("m", seed, "_", parts, ".pvtu"));
      ASSERT_TRUE(WritePvtu(path, Split(whole, parts)).ok());
      absl::StatusOr<MeshFile> read = ReadMesh(path);
      ASSERT_TRUE(read.ok()) << read.status();
      EXPECT_EQ(read->mesh.points, whole.mesh.points);
      EXPECT_EQ(read->mesh.tets, whole.mesh.tets);
      EXPECT_EQ(read->mesh.values, whole.mesh.values);
      EXPECT_EQ(read->mesh.labels, whole.mesh.labels);
      EXPECT_EQ(read->tet_iteration, whole.tet_iteration);
      EXPECT_EQ(read->tet_quality, whole.tet_quality);
      EXPECT_EQ(read->frame, whole.frame);
      EXPECT_EQ(read->label_name, whole.label_name);
    }
  }
}

TEST(IoPvtuReaderTest, RepeatedPointsWithinAPieceStayApart) {
  // Two tets with coincident but distinct vertices (a crack) in one piece: merging is only
  // between pieces, so the crack stays as the file has it.
  MeshFile a;
  a.mesh.points = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {1, 0, 0}};
  a.mesh.tets = {{0, 1, 2, 3}, {4, 2, 3, 0}};
  absl::StatusOr<MeshFile> merged = MergePvtuPieces({a}, {"a.vtu"});
  ASSERT_TRUE(merged.ok()) << merged.status();
  EXPECT_EQ(merged->mesh.points.size(), 5u);
  EXPECT_EQ(merged->mesh.tets, a.mesh.tets);
}

TEST(IoPvtuReaderTest, PiecesThatDisagreeAreRefusedNamingThePiece) {
  const MeshFile whole = Compacted(RandomMesh(3, {.labels = true}));
  std::vector<MeshFile> pieces = Split(whole, 2);
  pieces[1].tet_quality.clear();
  absl::StatusOr<MeshFile> merged = MergePvtuPieces(pieces, {"p_0.vtu", "p_1.vtu"});
  ASSERT_FALSE(merged.ok());
  EXPECT_THAT(std::string(merged.status().message()), HasSubstr("p_1.vtu: piece 1 holds"));

  pieces = Split(whole, 2);
  // A vertex of piece 1 that is also in piece 0, with another value there.
  size_t shared = 0;
  while (shared < pieces[1].mesh.points.size() &&
         std::find(pieces[0].mesh.points.begin(), pieces[0].mesh.points.end(),
                   pieces[1].mesh.points[shared]) == pieces[0].mesh.points.end()) {
    ++shared;
  }
  ASSERT_LT(shared, pieces[1].mesh.points.size());
  pieces[1].mesh.values[shared] += 1.0;
  merged = MergePvtuPieces(pieces, {"p_0.vtu", "p_1.vtu"});
  ASSERT_FALSE(merged.ok());
  EXPECT_THAT(std::string(merged.status().message()),
              HasSubstr(absl::StrCat("p_1.vtu: vertex ", shared, " of piece 1")));
}

TEST(IoPvtuReaderTest, BadIndexesNameTheFile) {
  ScratchDir dir;
  const std::string path = dir.File("bad.pvtu");
  const std::string head =
      "<?xml version=\"1.0\"?>\n<VTKFile type=\"PUnstructuredGrid\" version=\"1.0\">\n"
      "<PUnstructuredGrid GhostLevel=\"0\">\n<PPoints><PDataArray type=\"Float64\" "
      "NumberOfComponents=\"3\"/></PPoints>\n";
  const struct {
    std::string text;
    std::string says;
  } cases[] = {
      {head + "</PUnstructuredGrid>\n</VTKFile>\n", "the index names no pieces"},
      {head + "<Piece/>\n</PUnstructuredGrid>\n</VTKFile>\n", ":5: Piece has no Source file"},
      {head + "<Piece Source=\"missing_0.vtu\"/>\n</PUnstructuredGrid>\n</VTKFile>\n",
       "missing_0.vtu"},
      {"<VTKFile type=\"UnstructuredGrid\"><UnstructuredGrid/></VTKFile>",
       "VTKFile type \"UnstructuredGrid\" is not PUnstructuredGrid"},
  };
  for (const auto& c : cases) {
    SCOPED_TRACE(c.says);
    WriteBytes(path, c.text);
    absl::StatusOr<MeshFile> read = ReadMesh(path);
    ASSERT_FALSE(read.ok());
    EXPECT_THAT(std::string(read.status().message()), HasSubstr(path));
    EXPECT_THAT(std::string(read.status().message()), HasSubstr(c.says));
  }
  // A piece that is not a .vtu is that piece's error.
  WriteBytes(dir.File("junk_0.vtu"), "not xml");
  WriteBytes(path, head + "<Piece Source=\"junk_0.vtu\"/>\n</PUnstructuredGrid>\n</VTKFile>\n");
  absl::StatusOr<MeshFile> read = ReadMesh(path);
  ASSERT_FALSE(read.ok());
  EXPECT_THAT(std::string(read.status().message()), HasSubstr(dir.File("junk_0.vtu")));
}

TEST(IoPvtuReaderTest, APvtuIsNotWrittenAsOneMesh) {
  ScratchDir dir;
  EXPECT_TRUE(IsMeshPath("x.pvtu"));
  EXPECT_FALSE(IsWritableMeshPath("x.pvtu"));
  const absl::Status written = WriteMesh(dir.File("x.pvtu"), RandomMesh(1));
  ASSERT_FALSE(written.ok());
  EXPECT_THAT(std::string(written.message()), HasSubstr("written as pieces"));
}

}  // namespace
}  // namespace tetrefine::io::pvtu_reader_test
