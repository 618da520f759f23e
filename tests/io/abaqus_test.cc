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

// A set name with a control character, DEL included, is a region name without it (the fuzzer
// found a DEL that the reader kept and ValidateMeshFile then refused).
TEST(IoAbaqusTest, ControlCharactersLeaveSetNames) {
  std::string text(kCalculix);
  const size_t at = text.find("Core3");
  ASSERT_NE(at, std::string::npos);
  text.replace(at, 5,
               "Co\x7fre\x01"
               "3");
  absl::StatusOr<MeshFile> file = ParseAbaqus(text, "c.inp");
  ASSERT_TRUE(file.ok()) << file.status();
  EXPECT_EQ(file->region_names.at(3), "Core3");
  EXPECT_TRUE(ValidateMeshFile(*file, "c.inp").ok());
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

TEST(IoAbaqusTest, SetsNamingEarlierSetsHoldTheirElements) {
  const std::string head =
      "*NODE\n1,0,0,0\n2,1,0,0\n3,0,1,0\n4,0,0,1\n5,1,1,1\n6,2,2,2\n"
      "*ELEMENT, TYPE=C3D4, ELSET=Inner\n1,1,2,3,4\n2,2,3,4,5\n"
      "*ELEMENT, TYPE=C3D4, ELSET=Outer\n3,3,4,5,6\n";
  // The *ELEMENT blocks' sets are not regions once *ELSET blocks exist, but those can name them
  // (in any case); an element named twice in one set is no overlap.
  absl::StatusOr<MeshFile> file =
      ParseAbaqus(head + "*ELSET, ELSET=shell4\nOUTER\n*ELSET, ELSET=core2\ninner, 1\n", "s.inp");
  ASSERT_TRUE(file.ok()) << file.status();
  EXPECT_EQ(file->mesh.labels, (std::vector<int32_t>{2, 2, 4}));
  EXPECT_EQ(file->region_names.at(2), "core2");
  EXPECT_EQ(file->region_names.at(4), "shell4");
  // Sixty sets, each naming the one before twice: each is walked once, not 2^60 times.
  std::string chain = head + "*ELSET, ELSET=s0\ninner, inner\n";
  for (int i = 1; i < 60; ++i) {
    chain += absl::StrCat("*ELSET, ELSET=s", i, "\ns", i - 1, ", S", i - 1, "\n");
  }
  file = ParseAbaqus(chain, "s.inp");
  ASSERT_TRUE(file.ok()) << file.status();
  EXPECT_EQ(file->mesh.labels, (std::vector<int32_t>{1, 1, 0}));  // "s0"; the others overlap it
  // A set naming a later set is refused (a set names what is defined before it, as Abaqus reads
  // it), and an error in a named set is reported against that set.
  file = ParseAbaqus(head + "*ELSET, ELSET=a\nb, 3\n*ELSET, ELSET=b\n1, 2\n", "s.inp");
  ASSERT_FALSE(file.ok());
  EXPECT_THAT(std::string(file.status().message()),
              HasSubstr("s.inp:14: *ELSET a: \"b\" is neither an element id nor the name of an "
                        "earlier element set"));
  file = ParseAbaqus(head + "*ELSET, ELSET=bad\n9\n*ELSET, ELSET=all\nbad, 1\n", "s.inp");
  ASSERT_FALSE(file.ok());
  EXPECT_THAT(std::string(file.status().message()),
              HasSubstr("s.inp:13: element set bad names element 9"));
}

// Sets naming sets are walked once per set that names them, so a small file can ask for
// quadratic work (a long chain of sets each naming the one before, or many sets naming one big
// set): 2^15 sets naming one set of 2^14 + 1 ids stop at 2^28 walked ids.
TEST(IoAbaqusTest, SetsNamingSetsStopAt2To28WalkedIds) {
  std::string text = "*NODE\n1,0,0,0\n2,1,0,0\n3,0,1,0\n4,0,0,1\n*ELEMENT, TYPE=C3D4\n1,1,2,3,4\n";
  text += "*ELSET, ELSET=s0, GENERATE\n1, 1\n";
  text += "*ELSET, ELSET=big\n";
  for (int i = 0; i < 1 << 14; ++i) text += "1,\n";
  text += "1\n";
  for (int i = 1; i < 1 << 15; ++i) absl::StrAppend(&text, "*ELSET, ELSET=s", i, "\nbig\n");
  const absl::StatusOr<MeshFile> file = ParseAbaqus(text, "chain.inp");
  ASSERT_FALSE(file.ok());
  EXPECT_THAT(std::string(file.status().message()),
              HasSubstr("the element sets name more than 268435456 element ids in all"));
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
      {"*INCLUDE, INPUT=mesh.inp\n", "*INCLUDE is not followed"},
      {nodes + "*ELEMENT, TYPE=C3D4\n1,1,2,3,9\n", ":7: element 1: node \"9\" is not defined"},
      {nodes + "2,5,5,5\n", ":6: node 2 is defined twice"},
      {nodes + "*ELEMENT, TYPE=C3D4\n1,1,2,3\n", ":7: element 1 of type C3D4 has 3 nodes"},
      {"*NODE\n1,0,0\n", ":2: *NODE line has 3 fields"},
      {"*NODE\n1,0,nan,0\n", ":2: node 1: coordinate \"nan\""},
      {nodes + "*ELEMENT, TYPE=C3D4\n1,1,2,3,4\n*ELSET, ELSET=s\n1, 99\n",
       ":8: element set s names element 99"},
      {nodes + "*ELEMENT, TYPE=C3D4\n1,1,2,3,4\n*ELSET, ELSET=s\n1, other\n",
       "\"other\" is neither an element id nor the name of an earlier element set"},
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

// Abaqus/CAE's structured input: a part with its own numbering and sets, an assembly that
// places an instance of it (translated, then rotated), and an assembly set of that instance.
constexpr char kCaeHead[] = R"(*Heading
** Job name: block Model name: Model-1
*Preprint, echo=NO, model=NO, history=NO, contact=NO
**
** PARTS
**
*Part, name=Block
*Node
      1,           0.,           0.,           0.
      2,           1.,           0.,           0.
      3,           0.,           1.,           0.
      4,           0.,           0.,           1.
      5,           1.,           1.,           1.
*Element, type=C3D4
1, 1, 2, 3, 4
2, 2, 3, 4, 5
*Elset, elset=Core3
 1,
*Elset, elset=Rim8, generate
 2,  2,  1
*Solid Section, elset=Core3, material=Steel
,
*End Part
**
** ASSEMBLY
**
*Assembly, name=Assembly
**
)";

constexpr char kCaeTail[] = R"(*Nset, nset=Fixed, instance=Block-1
 1,
*Elset, elset=All, instance=Block-1, generate
 1,  2,  1
*End Assembly
**
** MATERIALS
**
*Material, name=Steel
*Elastic
210000., 0.3
)";

// Signed volume of tet t of `mesh`, six times over.
double Volume6(const Mesh& mesh, size_t t) {
  const auto& [a, b, c, d] = mesh.tets[t];
  const Vec3 &p = mesh.points[a], &q = mesh.points[b], &r = mesh.points[c], &s = mesh.points[d];
  const Vec3 u{q[0] - p[0], q[1] - p[1], q[2] - p[2]};
  const Vec3 v{r[0] - p[0], r[1] - p[1], r[2] - p[2]};
  const Vec3 w{s[0] - p[0], s[1] - p[1], s[2] - p[2]};
  return u[0] * (v[1] * w[2] - v[2] * w[1]) - u[1] * (v[0] * w[2] - v[2] * w[0]) +
         u[2] * (v[0] * w[1] - v[1] * w[0]);
}

TEST(IoAbaqusTest, CaePartPlacedByItsInstanceKeepsItsSets) {
  const std::string text = std::string(kCaeHead) +
                           "*Instance, name=Block-1, part=Block\n"
                           "10., 0., 0.\n"
                           "0., 0., 0., 0., 0., 1., 90.\n"
                           "*End Instance\n" +
                           kCaeTail;
  absl::StatusOr<MeshFile> file = ParseAbaqus(text, "cae.inp");
  ASSERT_TRUE(file.ok()) << file.status();
  ASSERT_EQ(file->mesh.points.size(), 5u);
  ASSERT_EQ(file->mesh.tets, (std::vector<Tet>{{0, 1, 2, 3}, {1, 2, 3, 4}}));
  // Translated by (10, 0, 0), then turned a quarter about z: (x, y, z) -> (-y, x + 10, z).
  const std::vector<Vec3> want = {{0, 10, 0}, {0, 11, 0}, {-1, 10, 0}, {0, 10, 1}, {-1, 11, 1}};
  for (size_t i = 0; i < want.size(); ++i) {
    for (int a = 0; a < 3; ++a) EXPECT_NEAR(file->mesh.points[i][a], want[i][a], 1e-12) << i;
  }
  // A rotation keeps each tet's orientation and volume.
  EXPECT_NEAR(Volume6(file->mesh, 0), 1.0, 1e-12);
  EXPECT_NEAR(Volume6(file->mesh, 1), 2.0, 1e-12);
  // The part's sets, then the assembly's "All" (which overlaps them and is not taken).
  EXPECT_EQ(file->mesh.labels, (std::vector<int32_t>{3, 8}));
  EXPECT_EQ(file->region_names.at(3), "Core3");
  EXPECT_EQ(file->region_names.at(8), "Rim8");
}

TEST(IoAbaqusTest, EveryInstanceIsPlacedAndItsSetsNamedAfterIt) {
  // Two instances of the block, the second moved clear of the first (keywords in other cases,
  // "*EndInstance" spelled without a space); a shell-only part's instance adds nothing.
  const std::string text = std::string(kCaeHead) +
                           "*INSTANCE, NAME=Block-1, PART=block\n*END INSTANCE\n"
                           "*instance, name=Block-2, part=Block\n5, 0, 0\n*EndInstance\n" +
                           kCaeTail;
  const std::string with_skin =
      "*Part, name=Skin\n*Node\n1,0,0,0\n2,1,0,0\n3,0,1,0\n*Element, type=S3\n1,1,2,3\n"
      "*End Part\n" +
      text;
  for (const std::string& t : {text, with_skin}) {
    std::string placed = t;
    if (&t == &with_skin) {
      placed.insert(placed.find("*End Assembly"),
                    "*Instance, name=Skin-1, part=Skin\n*End Instance\n");
    }
    absl::StatusOr<MeshFile> file = ParseAbaqus(placed, "two.inp");
    ASSERT_TRUE(file.ok()) << file.status();
    ASSERT_EQ(file->mesh.points.size(), 10u);
    EXPECT_EQ(file->mesh.tets,
              (std::vector<Tet>{{0, 1, 2, 3}, {1, 2, 3, 4}, {5, 6, 7, 8}, {6, 7, 8, 9}}));
    EXPECT_EQ(file->mesh.points[6], (Vec3{6, 0, 0}));
    // "Block-1.Core3" and "Block-2.Core3" share their trailing number: numbered in order.
    EXPECT_EQ(file->mesh.labels, (std::vector<int32_t>{1, 2, 3, 4}));
    EXPECT_EQ(file->region_names.at(1), "Block-1.Core3");
    EXPECT_EQ(file->region_names.at(4), "Block-2.Rim8");
  }
}

// Instances copy their part without the file holding the copies: a few kilobytes could ask for
// billions of tets. A part of 2^16 tets placed 2^12 + 1 times is refused before any copy.
TEST(IoAbaqusTest, InstancesMayNotPlaceMoreThan2To28Tets) {
  std::string text =
      "*Part, name=P\n*Node\n1,0,0,0\n2,1,0,0\n3,0,1,0\n4,0,0,1\n*Element, type=C3D4\n";
  for (int e = 1; e <= 1 << 16; ++e) absl::StrAppend(&text, e, ",1,2,3,4\n");
  text += "*End Part\n*Assembly, name=A\n";
  for (int i = 0; i <= 1 << 12; ++i) {
    absl::StrAppend(&text, "*Instance, name=I", i, ", part=P\n*End Instance\n");
  }
  text += "*End Assembly\n";
  const absl::StatusOr<MeshFile> file = ParseAbaqus(text, "many.inp");
  ASSERT_FALSE(file.ok());
  EXPECT_THAT(std::string(file.status().message()),
              HasSubstr("the instances up to I4096 place more than 268435456 tetrahedra"));
}

TEST(IoAbaqusTest, AssemblySetsLabelAPartWithoutSets) {
  std::string head = kCaeHead;
  head.erase(head.find("*Elset, elset=Core3"),
             head.find("*End Part") - head.find("*Elset, elset=Core3"));
  const std::string text = head +
                           "*Instance, name=Block-1, part=Block\n*End Instance\n"
                           "*Elset, elset=Front5, instance=Block-1\n2\n" +
                           kCaeTail;
  absl::StatusOr<MeshFile> file = ParseAbaqus(text, "asm.inp");
  ASSERT_TRUE(file.ok()) << file.status();
  // "Front5" takes tet 2, "All" then overlaps it and is not taken.
  EXPECT_EQ(file->mesh.labels, (std::vector<int32_t>{0, 5}));
  EXPECT_EQ(file->region_names.at(5), "Front5");
}

TEST(IoAbaqusTest, CaeStructureErrorsNameTheFileAndLine) {
  const std::string head = kCaeHead;
  const std::string instance = "*Instance, name=Block-1, part=Block\n*End Instance\n";
  const struct {
    std::string text;
    std::string says;
  } cases[] = {
      {head + "*Instance, name=Block-1\n*End Instance\n*End Assembly\n",
       "*INSTANCE Block-1 without PART="},
      {head + "*Instance, name=B, part=Cube\n*End Instance\n*End Assembly\n",
       "part Cube is not defined by an earlier *PART"},
      {head + "*End Assembly\n", "part Block has tetrahedra but no *INSTANCE"},
      {"*Part, name=Block\n*Node\n1,0,0,0\n", "the file ends inside *PART"},
      {head + "*Instance, name=B, part=Block\n1, 2\n*End Instance\n*End Assembly\n",
       "*INSTANCE B: expected a translation \"x, y, z\""},
      {head + "*Instance, name=B, part=Block\n0,0,0\n1,1,1,1,1,1,90\n*End Instance\n",
       "the rotation axis's two points are the same"},
      {head + "*Instance, name=B, part=Block\n0,0,0\n0,0,0,0,0,1,90\n1,2,3\n",
       "*INSTANCE B has more than two data lines"},
      {head + instance + instance, "instance Block-1 is defined twice"},
      {head + instance + "*Elset, elset=S, instance=Other\n1\n*End Assembly\n",
       "element set S names instance OTHER, which the assembly does not define"},
      {head + instance + "*Elset, elset=S, instance=Block-1\n7\n*End Assembly\n",
       "element set S names element 7, which part Block does not define"},
      {head + "*Instance, name=B, part=Block\n*Node\n1,0,0,0\n", "*NODE inside *INSTANCE"},
      {"*End Part\n", ":1: *END PART without *PART"},
      {head + "*Part, name=Two\n", "*PART inside another block"},
      {std::string("*Part, name=P\n*End Part\n*Part, name=p\n"), "part p is defined twice"},
      {"*Node\n1,0,0,0\n2,1,0,0\n3,0,1,0\n4,0,0,1\n*Element, type=C3D4\n1,1,2,3,4\n" + head +
           instance + "*End Assembly\n",
       ":6: elements outside *PART"},
  };
  for (const auto& c : cases) {
    SCOPED_TRACE(c.says);
    absl::StatusOr<MeshFile> file = ParseAbaqus(c.text, "cae.inp");
    ASSERT_FALSE(file.ok());
    EXPECT_THAT(std::string(file.status().message()), HasSubstr("cae.inp"));
    EXPECT_THAT(std::string(file.status().message()), HasSubstr(c.says));
  }
}

TEST(IoAbaqusTest, IncludedFilesStandInPlaceOfTheirKeyword) {
  // A CalculiX deck: the mesh in files of its own, one of them in a subdirectory and including
  // another (names relative to the deck's directory, at every depth).
  ScratchDir dir;
  std::filesystem::create_directory(dir.File("mesh"));
  WriteBytes(dir.File("deck.inp"),
             "*HEADING\nincluded\n*INCLUDE, INPUT=mesh/nodes.inp\n"
             "*include,input=\"mesh/elements.inp\"\n*MATERIAL, NAME=Steel\n");
  WriteBytes(dir.File("mesh/nodes.inp"),
             "*NODE, NSET=Nall\n10, 0, 0, 0\n20, 1, 0, 0\n30, 0, 1, 0\n40, 0, 0, 1\n50, 1, 1, 1\n");
  WriteBytes(dir.File("mesh/elements.inp"),
             "*ELEMENT, TYPE=C3D4, ELSET=Eall\n7, 10, 20, 30, 40\n9, 20, 30, 40, 50\n"
             "*INCLUDE, INPUT=mesh/sets.inp\n");
  WriteBytes(dir.File("mesh/sets.inp"), "*ELSET, ELSET=Core3\n7\n*ELSET, ELSET=Rim8\n9\n");
  absl::StatusOr<MeshFile> file = ReadMesh(dir.File("deck.inp"));
  ASSERT_TRUE(file.ok()) << file.status();
  EXPECT_EQ(file->mesh.points.size(), 5u);
  EXPECT_EQ(file->mesh.tets, (std::vector<Tet>{{0, 1, 2, 3}, {1, 2, 3, 4}}));
  EXPECT_EQ(file->mesh.labels, (std::vector<int32_t>{3, 8}));

  // An error in an included file names that file and its own line.
  WriteBytes(dir.File("mesh/sets.inp"), "*ELSET, ELSET=Core3\n7\n*ELSET, ELSET=Rim8\n99\n");
  file = ReadMesh(dir.File("deck.inp"));
  ASSERT_FALSE(file.ok());
  EXPECT_THAT(std::string(file.status().message()),
              HasSubstr("mesh/sets.inp:3: element set Rim8 names element 99"));
  // A missing file is named, with the line that includes it.
  WriteBytes(dir.File("mesh/elements.inp"), "*INCLUDE, INPUT=mesh/gone.inp\n");
  file = ReadMesh(dir.File("deck.inp"));
  ASSERT_FALSE(file.ok());
  EXPECT_THAT(std::string(file.status().message()),
              HasSubstr("mesh/elements.inp:1: *INCLUDE, INPUT=mesh/gone.inp: "));
  // A file that includes itself stops at the depth limit.
  WriteBytes(dir.File("mesh/elements.inp"), "** loop\n*INCLUDE, INPUT=mesh/elements.inp\n");
  file = ReadMesh(dir.File("deck.inp"));
  ASSERT_FALSE(file.ok());
  EXPECT_THAT(std::string(file.status().message()), HasSubstr("nested more than 8 deep"));
  WriteBytes(dir.File("mesh/elements.inp"), "*INCLUDE\n");
  file = ReadMesh(dir.File("deck.inp"));
  ASSERT_FALSE(file.ok());
  EXPECT_THAT(std::string(file.status().message()),
              HasSubstr("mesh/elements.inp:1: *INCLUDE without INPUT="));
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
