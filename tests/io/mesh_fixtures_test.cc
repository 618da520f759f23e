// Files written by real tools (tests/data/meshes, made by make_fixtures.py there with VTK 9.1,
// meshio and Gmsh 4.8): every variant reads as the same tetrahedra, labels, values and RAS
// points, and non-tet cells are skipped.
#include <string>
#include <vector>

#include "client/io/mesh_io.h"
#include "gtest/gtest.h"

namespace tetrefine::io {
namespace {

std::string FixturePath(const std::string& name) {
  return std::string(TETREFINE_SOURCE_DIR) + "/tests/data/meshes/" + name;
}

// The mesh of make_fixtures.py: a 2 x 3 x 1.5 box, six tets around its diagonal, two regions.
std::vector<Vec3> BoxCorners() {
  std::vector<Vec3> corners;
  for (double z : {0.0, 1.5}) {
    for (double y : {0.0, 3.0}) {
      for (double x : {0.0, 2.0}) corners.push_back({x, y, z});
    }
  }
  return corners;
}
const std::vector<Tet> kBoxTets = {{0, 1, 3, 7}, {0, 3, 2, 7}, {0, 2, 6, 7},
                                   {0, 6, 4, 7}, {0, 4, 5, 7}, {0, 5, 1, 7}};
const std::vector<int32_t> kBoxLabels = {1, 1, 1, 2, 2, 2};

struct FixtureCase {
  std::string file;
  std::string label_name;
  MeshFrame frame = MeshFrame::kUntagged;
  bool values = true;  // the format carries the point data "value"
};

void PrintTo(const FixtureCase& f, std::ostream* os) { *os << f.file; }

class IoFixtureTest : public ::testing::TestWithParam<FixtureCase> {};

TEST_P(IoFixtureTest, ReadsTheBoxWithItsLabels) {
  const FixtureCase& f = GetParam();
  absl::StatusOr<MeshFile> file = ReadMesh(FixturePath(f.file));
  ASSERT_TRUE(file.ok()) << file.status();
  EXPECT_EQ(file->mesh.points, BoxCorners());  // in RAS, whatever the file's frame
  EXPECT_EQ(file->mesh.tets, kBoxTets);
  EXPECT_EQ(file->mesh.labels, kBoxLabels);
  EXPECT_EQ(file->label_name, f.label_name);
  EXPECT_EQ(file->frame, f.frame);
  if (f.values) {
    std::vector<double> values;
    for (const Vec3& p : BoxCorners()) values.push_back(p[0] + 10 * p[1] + 100 * p[2]);
    EXPECT_EQ(file->mesh.values, values);
  }
}

std::vector<FixtureCase> AllFixtures() {
  std::vector<FixtureCase> all;
  for (const char* name : {"vtk9_ascii_none.vtu", "vtk9_binary_none.vtu", "vtk9_binary_zlib.vtu",
                           "vtk9_binary_lz4.vtu", "vtk9_binary_lzma.vtu", "vtk9_appended_none.vtu",
                           "vtk9_appended_zlib.vtu", "vtk9_appended_lz4.vtu",
                           "vtk9_appended_lzma.vtu", "vtk9_appended_base64_uint32_zlib.vtu"}) {
    all.push_back({name, "region"});
  }
  all.push_back({"slicer_lps.vtu", "region", MeshFrame::kLps});
  return all;
}

INSTANTIATE_TEST_SUITE_P(IoFixtures, IoFixtureTest, ::testing::ValuesIn(AllFixtures()),
                         [](const ::testing::TestParamInfo<FixtureCase>& info) {
                           std::string name = info.param.file;
                           for (char& c : name) c = std::isalnum(c) ? c : '_';
                           return name;
                         });

}  // namespace
}  // namespace tetrefine::io
