// `tetrefine refine --shards K --pvtu`: the result as a .pvtu index and K .vtu pieces, against two
// real tetrefine_server processes. The pieces hold exactly the merged result's tets (same
// corners, labels, iteration and quality), as this library and VTK's parallel reader see them.

#include <algorithm>
#include <array>
#include <cmath>
#include <memory>
#include <sstream>
#include <string>
#include <tuple>
#include <vector>

#include "absl/strings/match.h"
#include "absl/strings/str_cat.h"
#include "client/io/mesh_io.h"
#include "client/io/pvtu_writer.h"
#include "core/mesh.h"
#include "gtest/gtest.h"
#include "tests/cli/cli_test_util.h"
#include "tests/io/io_test_util.h"
#include "tests/support/geometry.h"

namespace tetrefine::clitest {
namespace {

using io::iotest::kPython;
using io::iotest::ReadBytes;
using io::iotest::ScratchDir;

// A tet by its corners' coordinates with what it carries, so that tets compare across vertex
// numberings.
using TetRecord = std::tuple<std::array<Vec3, 4>, int32_t, int32_t, float>;

std::vector<TetRecord> Records(const io::MeshFile& file) {
  std::vector<TetRecord> records;
  for (size_t t = 0; t < file.mesh.tets.size(); ++t) {
    std::array<Vec3, 4> corners;
    for (int c = 0; c < 4; ++c) corners[c] = file.mesh.points[file.mesh.tets[t][c]];
    records.emplace_back(corners, file.mesh.labels.empty() ? 0 : file.mesh.labels[t],
                         file.tet_iteration[t], file.tet_quality[t]);
  }
  return records;
}

double TotalVolume(const io::MeshFile& file) {
  double volume = 0.0;
  for (const Tet& t : file.mesh.tets) {
    const auto& p = file.mesh.points;
    volume += SignedVolume6(p[t[0]], p[t[1]], p[t[2]], p[t[3]]) / 6.0;
  }
  return volume;
}

// VTK's own parallel reader on the .pvtu: "cells points volume label_sum".
constexpr char kVtkScript[] = R"(
import sys
import vtk
from vtk.util.numpy_support import vtk_to_numpy
r = vtk.vtkXMLPUnstructuredGridReader()
r.SetFileName(sys.argv[1])
r.Update()
g = r.GetOutput()
assert (vtk_to_numpy(g.GetCellTypesArray()) == 10).all()
t = vtk_to_numpy(g.GetCells().GetConnectivityArray()).astype("int64").reshape(-1, 4)
p = vtk_to_numpy(g.GetPoints().GetData())
import numpy as np
a, b, c, d = p[t[:, 0]], p[t[:, 1]], p[t[:, 2]], p[t[:, 3]]
v = np.einsum("ij,ij->i", np.cross(b - a, c - a), d - a).sum() / 6.0
l = vtk_to_numpy(g.GetCellData().GetArray("region")).astype("int64")
print(g.GetNumberOfCells(), g.GetNumberOfPoints(), repr(float(v)), int(l.sum()))
)";

class CliPvtu : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    for (ServerProcess*& server : servers_) {
      absl::StatusOr<std::unique_ptr<ServerProcess>> started =
          ServerProcess::Start({"--threads=1"});
      if (!started.ok()) {
        start_error_ = new std::string(started.status().ToString());
        return;
      }
      server = started->release();
    }
  }
  static void TearDownTestSuite() {
    for (ServerProcess*& server : servers_) {
      delete server;
      server = nullptr;
    }
    delete start_error_;
    start_error_ = nullptr;
  }
  void SetUp() override {
    ASSERT_EQ(start_error_, nullptr) << *start_error_;
    volume_ = dir_.File("bump.nii");
    WriteVolume(volume_, BumpVolume({9, 9, 9}, {0.0, 0.0, 0.0}, {1.0, 1.0, 1.0}));
    io::MeshFile file;
    file.mesh = testing::FiveTetMesh({1, 1, 1}, {7, 7, 7}, {2, 2, 2});
    for (size_t t = 0; t < file.mesh.tets.size(); ++t) {
      file.mesh.labels.push_back(static_cast<int32_t>(1 + t % 3));
    }
    file.label_name = "region";
    mesh_ = dir_.File("labelled.vtu");
    ASSERT_TRUE(io::WriteMesh(mesh_, file).ok());
  }

  ProcessResult Refine(const std::vector<std::string>& extra) {
    std::vector<std::string> args = {
        "refine", "--volume", volume_,
        "--mesh", mesh_,      "--epsilon",
        "0.05",   "--server", absl::StrCat(servers_[0]->target(), ",", servers_[1]->target())};
    args.insert(args.end(), extra.begin(), extra.end());
    return RunTetrefine(args);
  }

  static std::array<ServerProcess*, 2> servers_;
  static std::string* start_error_;
  ScratchDir dir_;
  std::string volume_;
  std::string mesh_;
};

std::array<ServerProcess*, 2> CliPvtu::servers_ = {nullptr, nullptr};
std::string* CliPvtu::start_error_ = nullptr;

TEST_F(CliPvtu, PiecesHoldExactlyTheMergedResult) {
  const bool vtk = RunProcess({kPython, "-c", "import vtk, numpy"}).exit_code == 0;
  for (const char* scheme : {"longest-edge", "paper"}) {
    for (int shards : {2, 3, 5}) {
      SCOPED_TRACE(absl::StrCat(scheme, ", ", shards, " shards"));
      const std::string tag = absl::StrCat(scheme, shards);
      const std::string merged_path = dir_.File(tag + ".vtu");
      const std::string pvtu = dir_.File(tag + ".pvtu");
      const std::vector<std::string> common = {"--scheme", scheme, "--shards",
                                               std::to_string(shards), "--quiet"};
      std::vector<std::string> args = common;
      args.insert(args.end(), {"--output", merged_path});
      const ProcessResult merged_run = Refine(args);
      ASSERT_EQ(merged_run.exit_code, 0) << merged_run.err;
      args = common;
      args.insert(args.end(), {"--output", pvtu});
      const ProcessResult pvtu_run = Refine(args);
      ASSERT_EQ(pvtu_run.exit_code, 0) << pvtu_run.err;
      EXPECT_TRUE(absl::StrContains(pvtu_run.out, absl::StrCat(" (", shards, " .vtu pieces)")))
          << pvtu_run.out;

      absl::StatusOr<io::MeshFile> merged = io::ReadMesh(merged_path);
      ASSERT_TRUE(merged.ok()) << merged.status();
      ASSERT_GT(merged->mesh.tets.size(), 40u);
      const std::string index = ReadBytes(pvtu);
      std::vector<TetRecord> pieces;
      double pieces_volume = 0.0;
      for (int k = 0; k < shards; ++k) {
        const std::string piece_path = io::PvtuPiecePath(pvtu, k);
        EXPECT_TRUE(
            absl::StrContains(index, absl::StrCat("<Piece Source=\"", tag, "_", k, ".vtu\"/>")))
            << index;
        absl::StatusOr<io::MeshFile> piece = io::ReadMesh(piece_path);
        ASSERT_TRUE(piece.ok()) << piece.status();
        EXPECT_EQ(piece->label_name, "region");
        for (const TetRecord& r : Records(*piece)) pieces.push_back(r);
        pieces_volume += TotalVolume(*piece);
      }
      EXPECT_FALSE(FileExists(io::PvtuPiecePath(pvtu, shards)));
      std::vector<TetRecord> whole = Records(*merged);
      std::sort(whole.begin(), whole.end());
      std::sort(pieces.begin(), pieces.end());
      EXPECT_EQ(pieces, whole);
      const double volume = TotalVolume(*merged);
      EXPECT_NEAR(pieces_volume, volume, 1e-9 * volume);

      // Read back as one mesh, the pieces' shared vertices merged: the unsharded result's
      // vertices and tets, which `verify` finds conformal.
      absl::StatusOr<io::MeshFile> read_back = io::ReadMesh(pvtu);
      ASSERT_TRUE(read_back.ok()) << read_back.status();
      EXPECT_EQ(read_back->mesh.points.size(), merged->mesh.points.size());
      std::vector<TetRecord> again = Records(*read_back);
      std::sort(again.begin(), again.end());
      EXPECT_EQ(again, whole);
      const ProcessResult verified = RunTetrefine({"verify", "--volume", volume_, "--mesh", pvtu});
      EXPECT_EQ(verified.exit_code, 0) << verified.out << verified.err;
      EXPECT_TRUE(absl::StrContains(verified.out, "valid")) << verified.out;

      if (!vtk) continue;
      const ProcessResult read = RunProcess({kPython, "-c", kVtkScript, pvtu});
      ASSERT_EQ(read.exit_code, 0) << read.out << read.err;
      std::istringstream fields(read.out);
      long long cells = -1, points = -1, label_sum = -1;
      double vtk_volume = 0.0;
      fields >> cells >> points >> vtk_volume >> label_sum;
      EXPECT_EQ(cells, static_cast<long long>(merged->mesh.tets.size())) << read.out;
      // Boundary vertices are in every piece that has them.
      EXPECT_GE(points, static_cast<long long>(merged->mesh.points.size())) << read.out;
      EXPECT_NEAR(vtk_volume, volume, 1e-9 * volume) << read.out;
      long long want_labels = 0;
      for (int32_t l : merged->mesh.labels) want_labels += l;
      EXPECT_EQ(label_sum, want_labels);
    }
  }
  if (!vtk) GTEST_SKIP() << kPython << " cannot import vtk and numpy: VTK's reader not checked";
}

TEST_F(CliPvtu, PvtuFlagNamesTheIndexAfterTheOutput) {
  const std::string stats = dir_.File("named.json");
  const ProcessResult run = Refine({"--shards", "2", "--pvtu", "--output", dir_.File("named.vtu"),
                                    "--stats-json", stats, "--quiet"});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_TRUE(FileExists(dir_.File("named.pvtu")));
  EXPECT_TRUE(FileExists(dir_.File("named_0.vtu")));
  EXPECT_TRUE(FileExists(dir_.File("named_1.vtu")));
  EXPECT_FALSE(FileExists(dir_.File("named.vtu")));
  // The result is never merged: the statistics count the pieces' tets and vertices.
  int64_t tets = 0, vertices = 0;
  for (int k = 0; k < 2; ++k) {
    absl::StatusOr<io::MeshFile> piece = io::ReadMesh(dir_.File(absl::StrCat("named_", k, ".vtu")));
    ASSERT_TRUE(piece.ok()) << piece.status();
    tets += static_cast<int64_t>(piece->mesh.tets.size());
    vertices += static_cast<int64_t>(piece->mesh.points.size());
  }
  // Substrings rather than a JSON parser: nlohmann-json's header cost this test binary more
  // compile time than the check is worth (cli_refine_test.cc parses a document with Python).
  const std::string json = ReadBytes(stats);
  for (const std::string& field :
       {std::string("\"pieces\": 2"), absl::StrCat("\"vertices\": ", vertices),
        absl::StrCat("\"tets\": ", tets)}) {
    EXPECT_TRUE(absl::StrContains(json, field)) << field << " missing from\n" << json;
  }
  EXPECT_TRUE(absl::StrContains(
      run.out, absl::StrCat(vertices, " vertices over the pieces, ", tets, " tets")))
      << run.out;
}

TEST_F(CliPvtu, PiecesNeedAShardedRun) {
  for (const auto& [flags, named] : std::vector<std::pair<std::vector<std::string>, std::string>>{
           {{"--pvtu", "--output", "x.vtu"}, "--pvtu"}, {{"--output", "x.pvtu"}, "--output"}}) {
    std::vector<std::string> args = {"refine", "--volume",  volume_, "--mesh",
                                     mesh_,    "--epsilon", "0.05"};
    args.insert(args.end(), flags.begin(), flags.end());
    const ProcessResult run = RunTetrefine(args, dir_.path());
    EXPECT_EQ(run.exit_code, 2) << run.err;
    EXPECT_TRUE(absl::StrContains(run.err, named + ": a .pvtu holds one piece per shard"))
        << run.err;
  }
}

}  // namespace
}  // namespace tetrefine::clitest
