// The .pvtu writer: the index declares exactly the arrays each piece holds, with the names and
// types of the pieces' own DataArrays (what VTK's parallel reader checks), one Piece per file
// beside the index; pieces that disagree on their arrays are refused naming the piece.
#include "client/io/pvtu_writer.h"

#include <filesystem>
#include <fstream>
#include <set>
#include <string>
#include <tuple>
#include <vector>

#include "absl/strings/str_cat.h"
#include "client/io/mesh_io.h"
#include "gtest/gtest.h"
#include "pugixml.hpp"
#include "tests/io/io_test_util.h"

namespace tetrefine::io {
namespace {

using iotest::RandomMesh;
using iotest::RandomMeshOptions;
using iotest::ScratchDir;

// (Name, type, components) of every DataArray under `node`'s `section` child, or every
// PDataArray of the index's `section`.
std::set<std::tuple<std::string, std::string, std::string>> Arrays(pugi::xml_node section) {
  std::set<std::tuple<std::string, std::string, std::string>> arrays;
  for (pugi::xml_node a : section.children()) {
    arrays.emplace(a.attribute("Name").value(), a.attribute("type").value(),
                   a.attribute("NumberOfComponents").as_string("1"));
  }
  return arrays;
}

// Over random pieces with every combination of optional arrays: each section of the index lists
// what each piece's matching section holds, and the pieces read back as written.
TEST(IoPvtuTest, IndexDeclaresThePiecesArraysAndListsThemInOrder) {
  for (uint64_t seed = 1; seed <= 16; ++seed) {
    SCOPED_TRACE(seed);
    ScratchDir dir;
    RandomMeshOptions options;
    options.values = seed & 1;
    options.iteration = seed & 2;
    options.quality = seed & 4;
    options.labels = seed & 8;
    options.label_name = "CellEntityIds";
    std::vector<MeshFile> pieces;
    const int count = 1 + static_cast<int>(seed % 4);
    for (int k = 0; k < count; ++k) pieces.push_back(RandomMesh(seed * 100 + k, options));
    const std::string path = dir.File("result & co.pvtu");
    // ASCII pieces, so that pugixml can parse them whole (appended raw data is not XML).
    ASSERT_TRUE(WritePvtu(path, pieces, {.layout = VtuWriteOptions::Layout::kAscii}).ok());

    pugi::xml_document index;
    ASSERT_TRUE(index.load_file(path.c_str()));
    const pugi::xml_node grid = index.child("VTKFile").child("PUnstructuredGrid");
    EXPECT_STREQ(index.child("VTKFile").attribute("type").value(), "PUnstructuredGrid");
    std::vector<std::string> sources;
    for (pugi::xml_node piece : grid.children("Piece")) {
      sources.push_back(piece.attribute("Source").value());
    }
    ASSERT_EQ(static_cast<int>(sources.size()), count);
    for (int k = 0; k < count; ++k) {
      EXPECT_EQ(sources[k], absl::StrCat("result & co_", k, ".vtu"));
      EXPECT_EQ(PvtuPiecePath(path, k), dir.File(sources[k]));
      absl::StatusOr<MeshFile> back = ReadMesh(dir.File(sources[k]));
      ASSERT_TRUE(back.ok()) << back.status();
      EXPECT_EQ(back->mesh.tets, pieces[k].mesh.tets);
      EXPECT_EQ(back->mesh.labels, pieces[k].mesh.labels);

      pugi::xml_document vtu;
      ASSERT_TRUE(vtu.load_file(dir.File(sources[k]).c_str()));
      const pugi::xml_node piece = vtu.child("VTKFile").child("UnstructuredGrid").child("Piece");
      EXPECT_EQ(Arrays(grid.child("PPointData")), Arrays(piece.child("PointData")));
      EXPECT_EQ(Arrays(grid.child("PCellData")), Arrays(piece.child("CellData")));
      EXPECT_EQ(Arrays(grid.child("PPoints")), Arrays(piece.child("Points")));
    }
  }
}

TEST(IoPvtuTest, PiecesWithDifferentArraysAreRefusedNamingThePiece) {
  ScratchDir dir;
  RandomMeshOptions with;
  RandomMeshOptions without = with;
  without.quality = false;
  const std::vector<MeshFile> pieces = {RandomMesh(1, with), RandomMesh(2, with),
                                        RandomMesh(3, without)};
  const std::string path = dir.File("mixed.pvtu");
  const absl::Status status = WritePvtu(path, pieces);
  EXPECT_EQ(status.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_NE(status.message().find("piece 2"), std::string::npos) << status;
  EXPECT_FALSE(std::ifstream(path).good()) << "no index naming pieces that do not fit";

  const absl::Status none = WritePvtu(path, {});
  EXPECT_EQ(none.code(), absl::StatusCode::kInvalidArgument);
}

// A rewrite that fails part-way (here at piece 2 of 3, whose arrays differ) leaves the index
// and the pieces of the run before byte for byte, and no temporary: an outside review's re-run
// ran out of disk at piece 2 and left the old index over two new pieces and two old ones.
TEST(IoPvtuTest, AFailedRewriteLeavesTheFilesOfTheRunBefore) {
  ScratchDir dir;
  const std::string path = dir.File("result.pvtu");
  RandomMeshOptions with;
  ASSERT_TRUE(
      WritePvtu(path, {RandomMesh(1, with), RandomMesh(2, with), RandomMesh(3, with)}).ok());
  std::vector<std::string> before;
  before.push_back(iotest::ReadBytes(path));
  for (int k = 0; k < 3; ++k) before.push_back(iotest::ReadBytes(PvtuPiecePath(path, k)));
  RandomMeshOptions without = with;
  without.quality = false;
  ASSERT_FALSE(
      WritePvtu(path, {RandomMesh(4, with), RandomMesh(5, with), RandomMesh(6, without)}).ok());
  EXPECT_EQ(iotest::ReadBytes(path), before[0]);
  for (int k = 0; k < 3; ++k) {
    EXPECT_EQ(iotest::ReadBytes(PvtuPiecePath(path, k)), before[k + 1]) << "piece " << k;
  }
  int files = 0;
  for ([[maybe_unused]] const auto& entry : std::filesystem::directory_iterator(dir.path())) {
    ++files;
  }
  EXPECT_EQ(files, 4);
}

}  // namespace
}  // namespace tetrefine::io
