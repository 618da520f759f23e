// The .pvd collection writer: entries in order, file names relative to the .pvd, XML-escaped.
#include "client/io/pvd_writer.h"

#include <string>
#include <vector>

#include "absl/strings/str_cat.h"
#include "client/io/mesh_io.h"
#include "gmock/gmock.h"
#include "gtest/gtest.h"
#include "pugixml.hpp"
#include "tests/io/io_test_util.h"

namespace tetrefine::io {
namespace {

using iotest::ScratchDir;

TEST(IoPvdTest, ListsDatasetsRelativeToThePvd) {
  ScratchDir dir;
  std::vector<PvdEntry> entries;
  for (int i = 0; i < 3; ++i) {
    entries.push_back({.timestep = static_cast<double>(i),
                       .file = dir.File(absl::StrCat("out & co.iter0", i, ".vtu"))});
  }
  entries.push_back({.timestep = 2.5, .file = "/elsewhere/x.vtu", .part = 1});
  const std::string path = dir.File("series.pvd");
  ASSERT_TRUE(WritePvd(path, entries).ok());
  pugi::xml_document doc;
  ASSERT_TRUE(doc.load_file(path.c_str()));
  const pugi::xml_node root = doc.child("VTKFile");
  EXPECT_STREQ(root.attribute("type").value(), "Collection");
  std::vector<std::string> files;
  std::vector<double> steps;
  for (pugi::xml_node d : root.child("Collection").children("DataSet")) {
    files.push_back(d.attribute("file").value());
    steps.push_back(d.attribute("timestep").as_double());
  }
  EXPECT_THAT(files, ::testing::ElementsAre("out & co.iter00.vtu", "out & co.iter01.vtu",
                                            "out & co.iter02.vtu", "/elsewhere/x.vtu"));
  EXPECT_THAT(steps, ::testing::ElementsAre(0, 1, 2, 2.5));
}

// ParaView resolves a dataset's file against the .pvd's directory: every listed file must read
// from there, wherever the caller's working directory is. (Debian's VTK 9.1 Python has no .pvd
// reader to ask instead.)
TEST(IoPvdTest, EveryListedFileReadsFromThePvdDirectory) {
  ScratchDir dir;
  std::vector<PvdEntry> entries;
  for (int i = 0; i < 3; ++i) {
    iotest::RandomMeshOptions options;
    options.tets = 10 + 5 * i;
    const std::string file = dir.File(absl::StrCat("m.iter", i, ".vtu"));
    ASSERT_TRUE(WriteMesh(file, iotest::RandomMesh(i, options)).ok());
    entries.push_back({.timestep = static_cast<double>(i), .file = file});
  }
  const std::string path = dir.File("m.pvd");
  ASSERT_TRUE(WritePvd(path, entries).ok());
  pugi::xml_document doc;
  ASSERT_TRUE(doc.load_file(path.c_str()));
  size_t expected_tets = 10;
  for (pugi::xml_node d : doc.child("VTKFile").child("Collection").children("DataSet")) {
    const std::string file = d.attribute("file").value();
    EXPECT_EQ(file.find('/'), std::string::npos) << file;  // relative, beside the .pvd
    absl::StatusOr<MeshFile> mesh = ReadMesh(dir.File(file));
    ASSERT_TRUE(mesh.ok()) << mesh.status();
    EXPECT_EQ(mesh->mesh.tets.size(), expected_tets);
    expected_tets += 5;
  }
  EXPECT_EQ(expected_tets, 25u);
}

}  // namespace
}  // namespace tetrefine::io
