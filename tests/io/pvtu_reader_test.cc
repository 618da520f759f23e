// Reading a .pvtu as one mesh: the pieces' shared vertices merged, arrays in piece order, and
// errors naming the index or the piece.
#include "client/io/pvtu_reader.h"

#include <map>
#include <string>
#include <vector>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/strings/str_join.h"
#include "absl/strings/str_split.h"
#include "client/io/mesh_io.h"
#include "client/io/pvtu_writer.h"
#include "client/io/vtu_format.h"
#include "gmock/gmock.h"
#include "gtest/gtest.h"
#include "tests/io/io_test_util.h"
#include "tests/support/child_process.h"

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

// A .vtu with several <Piece>s (vtkXMLUnstructuredGridWriter with SetNumberOfPieces, which VTK
// and ParaView read) is one mesh, merged as a .pvtu's pieces are: it was refused (found by a
// file-format sweep).
TEST(IoPvtuReaderTest, SeveralPiecesInOneVtuMergeAsAPvtusPiecesDo) {
  for (uint64_t seed = 1; seed <= 6; ++seed) {
    RandomMeshOptions options;
    options.labels = seed % 2 == 0;
    options.values = seed % 3 != 0;
    const MeshFile whole = Compacted(RandomMesh(seed, options));
    for (int parts : {2, 3}) {
      SCOPED_TRACE(absl::StrCat("seed ", seed, ", ", parts, " pieces"));
      const VtuWriteOptions ascii{.layout = VtuWriteOptions::Layout::kAscii};
      std::string text;
      std::string more;
      for (const MeshFile& piece : Split(whole, parts)) {
        const std::string one = FormatVtu(piece, ascii);
        if (text.empty()) {
          text = one;
          continue;
        }
        const size_t begin = one.find("<Piece ");
        const size_t end = one.find("</Piece>") + std::string("</Piece>\n").size();
        more += one.substr(begin, end - begin);
      }
      text.insert(text.find("</UnstructuredGrid>"), more);
      absl::StatusOr<MeshFile> read = ParseVtu(text, "pieces.vtu");
      ASSERT_TRUE(read.ok()) << read.status();
      EXPECT_EQ(read->mesh.points, whole.mesh.points);
      EXPECT_EQ(read->mesh.tets, whole.mesh.tets);
      EXPECT_EQ(read->mesh.values, whole.mesh.values);
      EXPECT_EQ(read->mesh.labels, whole.mesh.labels);
    }
  }
}

// The bundled cube (without its labels unless keep_labels), written to `dir` as cube.vtu and
// passed by python3-vtk9 through vtkExtractUnstructuredGridPiece (`e`) to `writer`: Python lines
// that write from `e` into `d`, the directory. The cube as written, or the script's failure.
absl::StatusOr<MeshFile> CubeThroughVtkPieces(const ScratchDir& dir, bool keep_labels,
                                              const std::string& writer) {
  absl::StatusOr<MeshFile> cube =
      ReadMesh(std::string(TETREFINE_SOURCE_DIR) + "/examples/unit_cube_1782tets.mesh");
  if (!cube.ok()) return cube.status();
  if (!keep_labels) {
    cube->mesh.labels.clear();
    cube->label_name.clear();
  }
  if (absl::Status s = WriteMesh(dir.File("cube.vtu"), *cube); !s.ok()) return s;
  WriteBytes(
      dir.File("write.py"),
      "import sys, vtk\n"
      "d = sys.argv[1]\n"
      "r = vtk.vtkXMLUnstructuredGridReader(); r.SetFileName(d + '/cube.vtu')\n"
      "e = vtk.vtkExtractUnstructuredGridPiece(); e.SetInputConnection(r.GetOutputPort())\n" +
          writer);
  const testing::ProcessResult run =
      testing::RunProcess({iotest::kPython, dir.File("write.py"), dir.path()});
  if (run.exit_code != 0) return absl::InternalError(absl::StrCat("write.py: ", run.err));
  return cube;
}

// The same from VTK itself: vtkXMLUnstructuredGridWriter writing 3 pieces of the cube.
TEST(IoPvtuReaderTest, AVtuVtkWroteInThreePiecesReadsAsTheMesh) {
  if (testing::RunProcess({iotest::kPython, "-c", "import vtk"}).exit_code != 0) {
    GTEST_SKIP() << "python3-vtk9 is not installed";
  }
  ScratchDir dir;
  absl::StatusOr<MeshFile> cube = CubeThroughVtkPieces(
      dir, /*keep_labels=*/true,
      "w = vtk.vtkXMLUnstructuredGridWriter(); w.SetInputConnection(e.GetOutputPort())\n"
      "w.SetFileName(d + '/pieces.vtu'); w.SetNumberOfPieces(3); w.Write()\n");
  ASSERT_TRUE(cube.ok()) << cube.status();
  const std::vector<std::string> split =
      absl::StrSplit(iotest::ReadBytes(dir.File("pieces.vtu")), "<Piece ");
  ASSERT_EQ(split.size(), 4u);
  absl::StatusOr<MeshFile> read = ReadMesh(dir.File("pieces.vtu"));
  ASSERT_TRUE(read.ok()) << read.status();
  EXPECT_EQ(read->mesh.points.size(), cube->mesh.points.size());
  ASSERT_EQ(read->mesh.tets.size(), cube->mesh.tets.size());
  // Per region, to float32's precision (VTK's piece extraction stores points as float32).
  const std::map<int32_t, double> got = iotest::RegionVolumes(*read);
  const std::map<int32_t, double> want = iotest::RegionVolumes(*cube);
  ASSERT_EQ(got.size(), want.size());
  for (const auto& [label, volume] : want) EXPECT_NEAR(got.at(label), volume, 1e-6) << label;
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

// Tets `owned` and then `ghosts` of `whole` as one ASCII .vtu piece, numbered in first-use order,
// with vtkGhostType arrays as VTK's parallel writers add them for a ghost level: `ghost_flag` on
// the ghost cells (0 on the others), and 0 on every point (point flags are not read).
std::string GhostedPieceXml(const MeshFile& whole, const std::vector<size_t>& owned,
                            const std::vector<size_t>& ghosts, int ghost_flag) {
  std::vector<int64_t> local(whole.mesh.points.size(), -1);
  std::vector<uint32_t> points;
  std::vector<std::string> connectivity, offsets, types, cell_ghost, labels;
  const auto add = [&](size_t t, int flag) {
    for (uint32_t v : whole.mesh.tets[t]) {
      if (local[v] < 0) {
        local[v] = static_cast<int64_t>(points.size());
        points.push_back(v);
      }
      connectivity.push_back(absl::StrCat(local[v]));
    }
    offsets.push_back(absl::StrCat(connectivity.size()));
    types.push_back("10");
    cell_ghost.push_back(absl::StrCat(flag));
    if (!whole.mesh.labels.empty()) labels.push_back(absl::StrCat(whole.mesh.labels[t]));
  };
  for (size_t t : owned) add(t, 0);
  for (size_t t : ghosts) add(t, ghost_flag);
  std::vector<std::string> xyz, values, point_ghost;
  for (uint32_t v : points) {
    for (double c : whole.mesh.points[v]) xyz.push_back(absl::StrFormat("%.17g", c));
    if (!whole.mesh.values.empty())
      values.push_back(absl::StrFormat("%.17g", whole.mesh.values[v]));
    point_ghost.push_back("0");
  }
  const auto array = [](const char* type, const char* name, const std::vector<std::string>& v) {
    return absl::StrCat("<DataArray type=\"", type, "\" Name=\"", name, "\" format=\"ascii\">",
                        absl::StrJoin(v, " "), "</DataArray>\n");
  };
  return absl::StrCat(
      "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" "
      "byte_order=\"LittleEndian\" header_type=\"UInt64\">\n<UnstructuredGrid>\n"
      "<Piece NumberOfPoints=\"",
      points.size(), "\" NumberOfCells=\"", types.size(), "\">\n<PointData>\n",
      array("UInt8", "vtkGhostType", point_ghost),
      values.empty() ? "" : array("Float64", "value", values), "</PointData>\n<CellData>\n",
      array("UInt8", "vtkGhostType", cell_ghost),
      labels.empty() ? "" : array("Int32", "region", labels), "</CellData>\n<Points>\n",
      "<DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"ascii\">",
      absl::StrJoin(xyz, " "), "</DataArray>\n</Points>\n<Cells>\n",
      array("Int64", "connectivity", connectivity), array("Int64", "offsets", offsets),
      array("UInt8", "types", types), "</Cells>\n</Piece>\n</UnstructuredGrid>\n</VTKFile>\n");
}

// VTK's parallel writers, asked for ghost levels (a .pvtu with GhostLevel="1", ParaView's
// parallel "Save Data" of a dataset with ghost cells), repeat in each piece the neighbouring
// pieces' tets beside its own, flagged in vtkGhostType. Read as tets, every boundary tet came
// twice: refine refused the mesh ("the same tet ... listed twice") and `info` gave 2.8 times the
// unit cube's volume. The ghosts are skipped as VTK's RemoveGhostCells skips them: the merged
// mesh is the whole mesh, to the bit, whatever the pieces and the ghosts they carry.
TEST(IoPvtuReaderTest, GhostCellsOfEveryPieceAreSkipped) {
  ScratchDir dir;
  for (uint64_t seed = 1; seed <= 8; ++seed) {
    RandomMeshOptions options;
    options.labels = seed % 2 == 0;
    options.values = seed % 3 != 0;
    options.iteration = false;
    options.quality = false;
    const MeshFile whole = Compacted(RandomMesh(seed, options));
    const size_t n = whole.mesh.tets.size();
    for (int parts : {1, 2, 3}) {
      SCOPED_TRACE(absl::StrCat("seed ", seed, ", ", parts, " pieces"));
      std::string index =
          "<?xml version=\"1.0\"?>\n<VTKFile type=\"PUnstructuredGrid\" version=\"1.0\">\n"
          "<PUnstructuredGrid GhostLevel=\"1\">\n<PPoints><PDataArray type=\"Float64\" "
          "NumberOfComponents=\"3\"/></PPoints>\n";
      int64_t ghosts_written = 0;
      for (int k = 0; k < parts; ++k) {
        std::vector<size_t> owned, ghosts;
        for (size_t t = n * k / parts; t < n * (k + 1) / parts; ++t) owned.push_back(t);
        // Another piece's tets, and with one piece some of its own again.
        for (size_t t = (seed + k) % 3; t < n; t += 3) {
          if (parts == 1 || t < n * k / parts || t >= n * (k + 1) / parts) ghosts.push_back(t);
        }
        ghosts_written += static_cast<int64_t>(ghosts.size());
        const std::string piece = absl::StrCat("g", seed, "_", parts, "_", k, ".vtu");
        // DUPLICATECELL alone, and with HIDDENCELL (32) beside it.
        WriteBytes(dir.File(piece), GhostedPieceXml(whole, owned, ghosts, k % 2 == 0 ? 1 : 33));
        absl::StrAppend(&index, "<Piece Source=\"", piece, "\"/>\n");
      }
      absl::StrAppend(&index, "</PUnstructuredGrid>\n</VTKFile>\n");
      const std::string path = dir.File(absl::StrCat("g", seed, "_", parts, ".pvtu"));
      WriteBytes(path, index);
      absl::StatusOr<MeshFile> read = ReadMesh(path);
      ASSERT_TRUE(read.ok()) << read.status();
      EXPECT_EQ(read->mesh.points, whole.mesh.points);
      EXPECT_EQ(read->mesh.tets, whole.mesh.tets);
      EXPECT_EQ(read->mesh.values, whole.mesh.values);
      EXPECT_EQ(read->mesh.labels, whole.mesh.labels);
      EXPECT_EQ(read->ghost_cells_skipped, ghosts_written);
      EXPECT_TRUE(read->dropped_arrays.empty()) << absl::StrJoin(read->dropped_arrays, ", ");
    }
  }
}

TEST(IoPvtuReaderTest, OnlyTheDuplicateBitMakesAGhost) {
  // vtkGhostType's other bits (HIDDENCELL 32, REFINEDCELL 4, ...) leave a cell in, as
  // RemoveGhostCells leaves it; vtkGhostLevels (VTK before 7) marks ghosts by a level above 0.
  ScratchDir dir;
  const MeshFile whole = Compacted(RandomMesh(3));
  const std::vector<size_t> owned = {0, 1, 2, 3};
  const std::vector<size_t> others = {4, 5};
  WriteBytes(dir.File("kept.vtu"), GhostedPieceXml(whole, owned, others, 36));
  absl::StatusOr<MeshFile> kept = ReadMesh(dir.File("kept.vtu"));
  ASSERT_TRUE(kept.ok()) << kept.status();
  EXPECT_EQ(kept->mesh.tets.size(), 6u);
  EXPECT_EQ(kept->ghost_cells_skipped, 0);

  std::string levels = GhostedPieceXml(whole, owned, others, 1);
  for (size_t at; (at = levels.find("vtkGhostType")) != std::string::npos;) {
    levels.replace(at, 12, "vtkGhostLevels");
  }
  WriteBytes(dir.File("levels.vtu"), levels);
  absl::StatusOr<MeshFile> read = ReadMesh(dir.File("levels.vtu"));
  ASSERT_TRUE(read.ok()) << read.status();
  EXPECT_EQ(read->mesh.tets.size(), 4u);
  EXPECT_EQ(read->ghost_cells_skipped, 2);
  // The points only the ghosts used are gone with them, as RemoveGhostCells drops them.
  const MeshFile first_four = PieceOf(whole, 0, 4);
  EXPECT_EQ(read->mesh.points, first_four.mesh.points);
  EXPECT_EQ(read->mesh.tets, first_four.mesh.tets);
  EXPECT_EQ(read->mesh.values, first_four.mesh.values);

  std::string bad = GhostedPieceXml(whole, owned, others, 1);
  bad.replace(bad.find(">0 0 0 0 1 1<"), 13, ">0 0 0 0 1 256<");
  WriteBytes(dir.File("bad.vtu"), bad);
  absl::StatusOr<MeshFile> refused = ReadMesh(dir.File("bad.vtu"));
  ASSERT_FALSE(refused.ok());
  EXPECT_THAT(std::string(refused.status().message()),
              HasSubstr("cell 5: vtkGhostType 256 is not an unsigned 8-bit ghost flag"));
}

TEST(IoPvtuReaderTest, LegacyVtkGhostCellsAreSkippedToo) {
  // VTK's legacy writer keeps vtkGhostType as a cell SCALARS array.
  ScratchDir dir;
  const std::string text =
      "# vtk DataFile Version 5.1\nghosts\nASCII\nDATASET UNSTRUCTURED_GRID\n"
      "POINTS 5 double\n0 0 0 1 0 0 0 1 0 0 0 1 1 1 1\n"
      "CELLS 3 8\nOFFSETS vtktypeint64\n0 4 8\nCONNECTIVITY vtktypeint64\n0 1 2 3 1 2 3 4\n"
      "CELL_TYPES 2\n10\n10\n"
      "CELL_DATA 2\nSCALARS vtkGhostType unsigned_char 1\nLOOKUP_TABLE default\n0\n1\n";
  WriteBytes(dir.File("g.vtk"), text);
  absl::StatusOr<MeshFile> read = ReadMesh(dir.File("g.vtk"));
  ASSERT_TRUE(read.ok()) << read.status();
  EXPECT_EQ(read->mesh.tets, (std::vector<Tet>{{0, 1, 2, 3}}));
  EXPECT_EQ(read->mesh.points.size(), 4u);
  EXPECT_EQ(read->ghost_cells_skipped, 1);
}

// The real thing: VTK 9 (python3-vtk9) writes the unit cube as three pieces with one ghost level,
// in its default encoding (appended, zlib); read back, it is the cube again.
TEST(IoPvtuReaderTest, APvtuVtkWroteWithGhostLevelsReadsAsTheMesh) {
  if (testing::RunProcess({iotest::kPython, "-c", "import vtk"}).exit_code != 0) {
    GTEST_SKIP() << "python3-vtk9 is not installed";
  }
  ScratchDir dir;
  absl::StatusOr<MeshFile> cube = CubeThroughVtkPieces(
      dir, /*keep_labels=*/false,
      "w = vtk.vtkXMLPUnstructuredGridWriter(); w.SetInputConnection(e.GetOutputPort())\n"
      "w.SetFileName(d + '/ghosts.pvtu'); w.SetNumberOfPieces(3)\n"
      "w.SetStartPiece(0); w.SetEndPiece(2); w.SetGhostLevel(1); w.Write()\n");
  ASSERT_TRUE(cube.ok()) << cube.status();
  absl::StatusOr<MeshFile> read = ReadMesh(dir.File("ghosts.pvtu"));
  ASSERT_TRUE(read.ok()) << read.status();
  EXPECT_GT(read->ghost_cells_skipped, 0);
  EXPECT_EQ(read->mesh.points.size(), cube->mesh.points.size());
  // The same tets, as sets of corner coordinates (the pieces renumber the vertices, and VTK's
  // piece extraction stores points as float32).
  const auto corner_sets = [](const MeshFile& f) {
    std::vector<std::array<Vec3, 4>> out;
    for (const Tet& t : f.mesh.tets) {
      std::array<Vec3, 4> c;
      for (int k = 0; k < 4; ++k) {
        for (int a = 0; a < 3; ++a) c[k][a] = static_cast<float>(f.mesh.points[t[k]][a]);
      }
      std::sort(c.begin(), c.end());
      out.push_back(c);
    }
    std::sort(out.begin(), out.end());
    return out;
  };
  EXPECT_EQ(corner_sets(*read), corner_sets(*cube));
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
