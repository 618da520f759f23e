// Abaqus .inp as Gmsh, meshio and CalculiX write it: tets, regions from element sets, the
// blocks to skip, and errors naming the file and line.
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "absl/strings/str_cat.h"
#include "client/io/abaqus_format.h"
#include "client/io/mesh_io.h"
#include "gmock/gmock.h"
#include "gtest/gtest.h"
#include "tests/io/io_test_util.h"
#include "tests/support/child_process.h"

namespace tetrefine::io::abaqus_test {
namespace {

using iotest::kPython;
using iotest::ScratchDir;
using iotest::WriteBytes;
using ::testing::HasSubstr;

// The two unit cubes of two_cubes.geo: physical volumes 5 and 7, each of volume 1, named after
// Gmsh's sets.
void ExpectTwoCubes(const MeshFile& file) {
  EXPECT_EQ(file.mesh.tets.size(), 200u);
  const std::map<int32_t, double> volume = iotest::RegionVolumes(file);
  ASSERT_EQ(volume.size(), 2u);
  EXPECT_NEAR(volume.at(5), 1.0, 1e-12);
  EXPECT_NEAR(volume.at(7), 1.0, 1e-12);
  EXPECT_EQ(file.region_names.at(5), "PhysicalVolume5");
  EXPECT_EQ(file.region_names.at(7), "PhysicalVolume7");
}

TEST(IoAbaqusTest, GmshsInputReadsWithItsPhysicalVolumes) {
  absl::StatusOr<MeshFile> file = ReadMesh(iotest::MeshFixture("gmsh_two_cubes.inp"));
  ASSERT_TRUE(file.ok()) << file.status();
  ExpectTwoCubes(*file);
}

TEST(IoAbaqusTest, MeshiosInputReadsTheSame) {
  if (testing::RunProcess({kPython, "-c", "import meshio"}).exit_code != 0) {
    GTEST_SKIP() << "meshio is not installed";
  }
  ScratchDir dir;
  const testing::ProcessResult run = testing::RunProcess(
      {kPython, "-c",
       absl::StrCat("import meshio; meshio.write('", dir.File("m.inp"), "', meshio.read('",
                    iotest::MeshFixture("gmsh_two_cubes.inp"), "'))")});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  absl::StatusOr<MeshFile> file = ReadMesh(dir.File("m.inp"));
  ASSERT_TRUE(file.ok()) << file.status();
  ExpectTwoCubes(*file);
}

// CalculiX-style input with what a reader must get through: a heading, lower-case keywords,
// comments, ids that are neither consecutive nor from 1, continuation lines, a shell element,
// GENERATE sets, material and step blocks.
constexpr char kCalculix[] = R"(*HEADING
a two-tet model
** a comment
*node, nset=Nall
10, 0, 0, 0
20, 1, 0, 0
30, 0, 1, 0
40, 0, 0, 1
50, 1, 1, 1
*ELEMENT, TYPE=C3D4, ELSET=Eall
7, 10, 20, 30,
   40
9, 20, 30, 40, 50
*ELEMENT, TYPE=S3, ELSET=Skin
100, 10, 20, 30
*ELSET, ELSET=Core3
7
*ELSET, ELSET=Rim8, GENERATE
9, 9, 1
*MATERIAL, NAME=Steel
*ELASTIC
210000, 0.3
*STEP
*STATIC
*END STEP
)";

TEST(IoAbaqusTest, CalculixStyleInputReads) {
  absl::StatusOr<MeshFile> file = ParseAbaqus(kCalculix, "c.inp");
  ASSERT_TRUE(file.ok()) << file.status();
  EXPECT_EQ(file->mesh.points.size(), 5u);
  EXPECT_EQ(file->mesh.tets, (std::vector<Tet>{{0, 1, 2, 3}, {1, 2, 3, 4}}));
  // The *ELSET blocks are the regions, labelled by their trailing numbers.
  EXPECT_EQ(file->mesh.labels, (std::vector<int32_t>{3, 8}));
  EXPECT_EQ(file->region_names.at(3), "Core3");
  EXPECT_EQ(file->region_names.at(8), "Rim8");
}

TEST(IoAbaqusTest, OverlappingSetsGiveTheFirstAndUnnumberedSetsCount) {
  const std::string head =
      "*NODE\n1,0,0,0\n2,1,0,0\n3,0,1,0\n4,0,0,1\n5,1,1,1\n6,2,2,2\n"
      "*ELEMENT, TYPE=C3D4\n1,1,2,3,4\n2,2,3,4,5\n3,3,4,5,6\n";
  // "whole" overlaps "left" and is not taken; tet 3 is in no set taken: label 0. Names without
  // a trailing number: the taken sets are numbered in file order.
  absl::StatusOr<MeshFile> file = ParseAbaqus(
      head + "*ELSET, ELSET=left\n1\n*ELSET, ELSET=whole\n1,2,3\n*ELSET, ELSET=right\n2\n",
      "o.inp");
  ASSERT_TRUE(file.ok()) << file.status();
  EXPECT_EQ(file->mesh.labels, (std::vector<int32_t>{1, 2, 0}));
  EXPECT_EQ(file->region_names.at(1), "left");
  EXPECT_EQ(file->region_names.at(2), "right");
  // No sets: no labels.
  file = ParseAbaqus(head, "o.inp");
  ASSERT_TRUE(file.ok()) << file.status();
  EXPECT_TRUE(file->mesh.labels.empty());
}

TEST(IoAbaqusTest, ErrorsNameTheFileAndLine) {
  const std::string nodes = "*NODE\n1,0,0,0\n2,1,0,0\n3,0,1,0\n4,0,0,1\n";
  const struct {
    std::string text;
    std::string says;
  } cases[] = {
      {nodes + "*ELEMENT, TYPE=C3D10\n1,1,2,3,4,1,2,3,4,1,2\n",
       "1 C3D10 element and no tetrahedra"},
      {nodes + "*ELEMENT, TYPE=C3D4\n1,1,2,3,4\n*ELEMENT, TYPE=C3D8R\n2,1,2,3,4,1,2,3,4\n",
       "1 C3D8R element beside 1 tetrahedron"},
      {"*PART, NAME=Part-1\n" + nodes, "line 1: *PART: Abaqus/CAE parts and instances"},
      {"*INCLUDE, INPUT=mesh.inp\n", "*INCLUDE is not followed"},
      {nodes + "*ELEMENT, TYPE=C3D4\n1,1,2,3,9\n", ":7: element 1: node \"9\" is not defined"},
      {nodes + "2,5,5,5\n", ":6: node 2 is defined twice"},
      {nodes + "*ELEMENT, TYPE=C3D4\n1,1,2,3\n", ":7: element 1 of type C3D4 has 3 nodes"},
      {"*NODE\n1,0,0\n", ":2: *NODE line has 3 fields"},
      {"*NODE\n1,0,nan,0\n", ":2: node 1: coordinate \"nan\""},
      {nodes + "*ELEMENT, TYPE=C3D4\n1,1,2,3,4\n*ELSET, ELSET=s\n1, 99\n",
       ":8: element set s names element 99"},
      {nodes + "*ELEMENT, TYPE=C3D4\n1,1,2,3,4\n*ELSET, ELSET=s\n1, other\n",
       "sets of sets are not read"},
      // Four billion generated ids are an error at the second, not four billion allocations.
      {nodes + "*ELEMENT, TYPE=C3D4\n1,1,2,3,4\n*ELSET, ELSET=s, GENERATE\n1, 4000000000\n",
       ":8: element set s names element 2, which the file does not define"},
      {nodes + "*ELEMENT\n1,1,2,3,4\n", ":6: *ELEMENT without TYPE="},
      {"1, 2, 3\n", ":1: data line outside any keyword block"},
  };
  for (const auto& c : cases) {
    SCOPED_TRACE(c.says);
    absl::StatusOr<MeshFile> file = ParseAbaqus(c.text, "bad.inp");
    ASSERT_FALSE(file.ok());
    EXPECT_THAT(std::string(file.status().message()), HasSubstr("bad.inp"));
    EXPECT_THAT(std::string(file.status().message()), HasSubstr(c.says));
  }
  const std::string good = kCalculix;
  for (size_t size = 0; size < good.size(); size += 3) {
    const absl::StatusOr<MeshFile> file = ParseAbaqus(good.substr(0, size), "cut.inp");
    if (!file.ok()) {
      EXPECT_THAT(std::string(file.status().message()), HasSubstr("cut.inp"));
    } else {
      EXPECT_TRUE(ValidateMeshFile(*file, "cut.inp").ok());
    }
  }
}

TEST(IoAbaqusTest, InpIsReadNotWritten) {
  EXPECT_TRUE(IsMeshPath("x.inp"));
  EXPECT_FALSE(IsWritableMeshPath("x.inp"));
  ScratchDir dir;
  absl::StatusOr<MeshFile> file = ReadMesh(iotest::MeshFixture("gmsh_two_cubes.inp"));
  ASSERT_TRUE(file.ok());
  EXPECT_THAT(std::string(WriteMesh(dir.File("x.inp"), *file).message()),
              HasSubstr("read, not written"));
  // Written as .msh, the set names come along as Gmsh's physical names.
  ASSERT_TRUE(WriteMesh(dir.File("x.msh"), *file).ok());
  absl::StatusOr<MeshFile> back = ReadMesh(dir.File("x.msh"));
  ASSERT_TRUE(back.ok()) << back.status();
  EXPECT_EQ(back->region_names, file->region_names);
  EXPECT_EQ(back->mesh.labels.size(), file->mesh.labels.size());
}

}  // namespace
}  // namespace tetrefine::io::abaqus_test
