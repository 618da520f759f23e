// Malformed mesh files: every reader returns an error naming the file, never crashes, and never
// allocates from a count the file cannot back up.
#include <cctype>
#include <limits>
#include <ostream>
#include <random>
#include <string>

#include "absl/strings/match.h"
#include "absl/strings/str_replace.h"
#include "client/io/gmsh_format.h"
#include "client/io/medit_format.h"
#include "client/io/mesh_io.h"
#include "client/io/vtk_legacy_format.h"
#include "client/io/vtu_format.h"
#include "gmock/gmock.h"
#include "gtest/gtest.h"
#include "tests/io/io_test_util.h"

namespace tetrefine::io {
namespace {

using iotest::RandomMesh;
using iotest::RandomMeshOptions;
using iotest::ScratchDir;
using iotest::WriteBytes;
using ::testing::HasSubstr;

MeshFile SmallMesh() {
  RandomMeshOptions options;
  options.vertices = 6;
  options.tets = 4;
  options.labels = true;
  return RandomMesh(11, options);
}

// ".b64.vtu" stands for a .vtu with inline base64 arrays (read as .vtu, by extension).
std::string Written(const std::string& extension, const MeshFile& mesh) {
  if (extension == ".b64.vtu") {
    return FormatVtu(mesh, {.layout = VtuWriteOptions::Layout::kInlineBase64,
                            .compressor = VtkCompressor::kNone});
  }
  if (extension == ".asc.vtu") return FormatVtu(mesh, {.layout = VtuWriteOptions::Layout::kAscii});
  if (extension == ".vtu") return FormatVtu(mesh);
  if (extension == ".vtk") return FormatVtkLegacy(mesh);
  if (extension == ".bin.vtk") return FormatVtkLegacy(mesh, {.binary = true});
  if (extension == ".msh") return FormatGmsh41(mesh);
  if (extension == ".bin.msh") return FormatGmsh41(mesh, {.binary = true});
  if (extension == ".meshb") return FormatMeshb(mesh);
  return FormatMedit(mesh);
}

class IoMeshMalformedTest : public ::testing::TestWithParam<std::string> {
 protected:
  std::string Path(const std::string& stem) const { return dir_.File(stem + GetParam()); }

  // Reads `bytes` as a file of this format; must fail with the path in the message.
  void ExpectError(const std::string& bytes, const std::string& context) {
    const std::string path = Path("bad");
    WriteBytes(path, bytes);
    absl::StatusOr<MeshFile> file = ReadMesh(path);
    ASSERT_FALSE(file.ok()) << context;
    EXPECT_THAT(std::string(file.status().message()), HasSubstr(path)) << context;
  }

  ScratchDir dir_;
};

// True when cutting `bytes` at `size` leaves a file that ends between sections, or inside the
// final token of a section (the next line starts a keyword: a letter or '$'). Gmsh's trailing
// data sections are optional and legacy VTK and Medit (whose "End" is optional) have no end
// marker, so such a file is complete and merely different ("10" cut to "1", later sections
// gone); no reader can tell. Every other cut must fail.
bool CutsAtSectionEnd(const std::string& bytes, size_t size) {
  const auto keyword_start = [](char c) {
    return std::isalpha(static_cast<unsigned char>(c)) || c == '$';
  };
  if (size > 0 && bytes[size - 1] == '\n' && keyword_start(bytes[size])) return true;
  const size_t newline = bytes.find('\n', size);
  if (newline == std::string::npos) return true;
  if (bytes.substr(size, newline - size).find(' ') != std::string::npos) return false;
  if (size > 0 && bytes[size - 1] == ' ') return false;
  return newline + 1 >= bytes.size() || keyword_start(bytes[newline + 1]);
}

TEST_P(IoMeshMalformedTest, EveryTruncationFails) {
  const MeshFile mesh = SmallMesh();
  const std::string bytes = Written(GetParam(), mesh);
  const std::string path = Path("cut");
  size_t last_token = bytes.find_last_not_of(" \n");
  last_token = bytes.find_last_of(" \n", last_token) + 1;
  for (size_t size = 0; size < last_token; ++size) {
    SCOPED_TRACE(::testing::Message() << "truncated to " << size << " of " << bytes.size());
    WriteBytes(path, bytes.substr(0, size));
    absl::StatusOr<MeshFile> file = ReadMesh(path);
    if (!file.ok()) {
      EXPECT_THAT(std::string(file.status().message()), HasSubstr(path));
      continue;
    }
    EXPECT_FALSE(absl::EndsWith(GetParam(), ".vtu"));  // XML must be closed
    EXPECT_TRUE(CutsAtSectionEnd(bytes, size));
    EXPECT_EQ(file->mesh.points, mesh.mesh.points);
  }
}

TEST_P(IoMeshMalformedTest, RandomCorruptionNeverCrashes) {
  const std::string bytes = Written(GetParam(), SmallMesh());
  const std::string path = Path("fuzz");
  std::mt19937_64 rng(5);
  for (int trial = 0; trial < 300; ++trial) {
    std::string corrupt = bytes;
    const int edits = 1 + static_cast<int>(rng() % 4);
    for (int e = 0; e < edits; ++e) {
      const size_t at = rng() % corrupt.size();
      switch (rng() % 3) {
        case 0:
          corrupt[at] = static_cast<char>(rng());
          break;
        case 1:
          corrupt[at] = "0123456789-.e \n"[rng() % 15];
          break;
        default:
          corrupt.insert(at, std::to_string(rng()));  // huge numbers, e.g. in counts
      }
    }
    WriteBytes(path, corrupt);
    absl::StatusOr<MeshFile> file = ReadMesh(path);
    if (file.ok()) {
      EXPECT_TRUE(ValidateMeshFile(*file, path).ok());
    } else {
      EXPECT_THAT(std::string(file.status().message()), HasSubstr(path));
    }
  }
  std::string garbage(4096, '\0');
  for (char& c : garbage) c = static_cast<char>(rng());
  ExpectError(garbage, "garbage");
  ExpectError("", "empty file");
}

// Text edits that make the mesh invalid, per format: {from, to, why}.
struct Edit {
  std::string extension;
  std::string from;
  std::string to;
  std::string message;  // expected in the error
};

void PrintTo(const Edit& edit, std::ostream* os) {
  *os << edit.extension << ": \"" << edit.from << "\" -> \"" << edit.to << "\"";
}

class IoMeshBadContentTest : public ::testing::TestWithParam<Edit> {};

// Found by a CLI sweep: a NaN in a "value" point array or a "quality" cell array, which refine
// and verify compute again, made refine, verify and info refuse a usable mesh. The array is
// dropped and named with its first bad entry; the mesh reads.
TEST(IoMeshTest, NonFiniteDerivedArraysAreDroppedNotTheMesh) {
  RandomMeshOptions options;
  options.vertices = 5;
  options.tets = 2;
  MeshFile mesh = RandomMesh(2, options);
  mesh.mesh.tets[0] = {0, 1, 2, 3};
  mesh.mesh.values[0] = 0.75;
  std::string bytes = Written(".vtk", mesh);
  ASSERT_THAT(bytes, HasSubstr("\n0.75\n"));
  bytes = absl::StrReplaceAll(bytes, {{"\n0.75\n", "\nnan\n"}});
  ScratchDir dir;
  const std::string path = dir.File("nan_value.vtk");
  WriteBytes(path, bytes);
  absl::StatusOr<MeshFile> read = ReadMesh(path);
  ASSERT_TRUE(read.ok()) << read.status();
  EXPECT_TRUE(read->mesh.values.empty());
  EXPECT_EQ(read->mesh.tets, mesh.mesh.tets);
  ASSERT_EQ(read->dropped_arrays.size(), 1u);
  EXPECT_EQ(read->dropped_arrays[0], "point data \"value\" (not finite at vertex 0: nan)");

  MeshFile quality = mesh;
  quality.tet_quality[1] = std::numeric_limits<float>::infinity();
  DropNonFiniteDerivedArrays(&quality);
  EXPECT_TRUE(quality.tet_quality.empty());
  EXPECT_EQ(quality.dropped_arrays.back(), "cell data \"quality\" (not finite at tet 1: inf)");
  // Writers still refuse them: what tetrefine writes is finite.
  mesh.tet_quality[0] = std::numeric_limits<float>::quiet_NaN();
  EXPECT_FALSE(WriteMesh(dir.File("out.vtu"), mesh).ok());
}

TEST_P(IoMeshBadContentTest, ClearError) {
  const Edit& edit = GetParam();
  RandomMeshOptions options;
  options.vertices = 5;
  options.tets = 2;
  MeshFile mesh = RandomMesh(2, options);
  mesh.mesh.points[0] = {0.125, 0.25, 0.5};
  mesh.mesh.tets[0] = {0, 1, 2, 3};
  mesh.mesh.values[0] = 0.75;
  std::string bytes = Written(edit.extension, mesh);
  ASSERT_THAT(bytes, HasSubstr(edit.from));
  bytes = absl::StrReplaceAll(bytes, {{edit.from, edit.to}});
  ScratchDir dir;
  const std::string path = dir.File("bad" + edit.extension);
  WriteBytes(path, bytes);
  const absl::Status status = ReadMesh(path).status();
  ASSERT_FALSE(status.ok());
  EXPECT_THAT(std::string(status.message()), HasSubstr(path));
  EXPECT_THAT(std::string(status.message()), HasSubstr(edit.message));
}

// A legacy VTK file's three header lines are named by their own line numbers (they were named one
// line too late: an outside review, 2026-11-28).
TEST(IoMeshTest, LegacyVtkHeaderErrorsNameTheirLine) {
  ScratchDir dir;
  for (const auto& [text, message] : std::vector<std::pair<std::string, std::string>>{
           {"hello\nworld\n", "bad.vtk:1: not a legacy VTK file"},
           {"# vtk DataFile Version x\ntitle\nASCII\n", "bad.vtk:1: bad legacy VTK version"},
           {"# vtk DataFile Version 3.0\ntitle\nASCIX\nDATASET UNSTRUCTURED_GRID\n",
            "bad.vtk:3: third line must be ASCII or BINARY"}}) {
    WriteBytes(dir.File("bad.vtk"), text);
    EXPECT_THAT(std::string(ReadMesh(dir.File("bad.vtk")).status().message()), HasSubstr(message));
  }
}

INSTANTIATE_TEST_SUITE_P(
    IoEdits, IoMeshBadContentTest,
    ::testing::Values(
        // Declared counts larger than the file: refused before allocating.
        Edit{".mesh", "Vertices\n5\n", "Vertices\n5000000000\n", "out of range"},
        Edit{".mesh", "Tetrahedra\n2\n", "Tetrahedra\n2000000000\n", "bytes remain"},
        Edit{".mesh", "Tetrahedra\n2\n", "Tetrahedra\n3\n", "bytes remain"},
        Edit{".mesh", "1 2 3 4 ", "1 2 3 9 ", "out of range"},
        Edit{".mesh", "0.125 0.25 0.5", "0.125 nan 0.5", "not finite"},
        Edit{".vtk", "POINTS 5 double", "POINTS 4000000 double", "bytes remain"},
        Edit{".vtk", "CELLS 2 10\n4 0 1 2 3", "CELLS 2 10\n4 0 1 2 7", "out of range"},
        Edit{".vtk", "0.125 0.25 0.5", "0.125 0.25 nan", "non-finite"},
        Edit{".vtk", "POINT_DATA 5", "POINT_DATA 6", "does not match"},
        Edit{".msh", "$Nodes\n1 5 1 5\n3 1 0 5", "$Nodes\n1 5 1 5\n3 1 0 4", "header says 5"},
        Edit{".msh", "1 1 2 3 4\n", "1 1 2 3 9\n", "not defined"},
        Edit{".msh", "0.125 0.25 0.5", "0.125 0.25 inf", "not finite"},
        Edit{".msh", "$Elements\n1 2 1 2", "$Elements\n1 200000000000 1 2", "bytes remain"},
        Edit{".msh", "$EndNodes", "$EndNodez", "expected $EndNodes"},
        // MSH 2 with Mesh.SaveParametric: was "$Elements before $Nodes".
        Edit{".msh", "$Nodes\n", "$ParametricNodes\n", "$ParametricNodes (MSH 2 nodes with"},
        Edit{".vtu", "NumberOfPoints=\"5\"", "NumberOfPoints=\"6\"", "header says"},
        Edit{".vtu", "NumberOfCells=\"2\"", "NumberOfCells=\"99999999999\"", "header says"},
        Edit{".vtu", "</Points>", "</Pointz>", "not well-formed XML"},
        Edit{".vtu", "offset=\"0\"", "offset=\"99999\"", "bad appended offset"},
        Edit{".vtu", "vtkZLibDataCompressor", "vtkZstdDataCompressor", "is not supported"},
        Edit{".vtu", "encoding=\"raw\"", "encoding=\"hex\"", "neither raw nor base64"},
        Edit{".vtu", "</VTKFile>", "</VTKFil", "does not end with"},
        Edit{".bin.vtk", "BINARY", "BINARX", "ASCII or BINARY"},
        Edit{".bin.vtk", "POINTS 5 double", "POINTS 6 double", "unexpected keyword"},
        Edit{".bin.vtk", "CELL_TYPES 2", "CELL_TYPES 3", "unexpected keyword"},
        Edit{".vtk", "CELL_TYPES 2\n10\n", "CELL_TYPES 2\n24\n",
             "1 quadratic tetrahedron (tetra10) beside 1 tetrahedron"},
        Edit{".vtk", "DATASET UNSTRUCTURED_GRID\n", "DATASET UNSTRUCTURED_GRID\nMETADATA\nX\n",
             "are all required"},
        Edit{".bin.msh", "4.1 1 8", "4.1 1 4", "data size 4"},
        Edit{".bin.msh", "$EndElements", "$EndElementz", "expected $EndElements"},
        Edit{".bin.msh", "$EndNodes", "", "expected $EndNodes"},
        Edit{".msh", "3 1 4 2\n", "3 1 99 2\n", "unknown element type 99"},
        Edit{".msh", "0 0 0 1\n1 ", "0 0 0 1\n1e3 ", "an entity tag"},
        Edit{".mesh", "Tetrahedra\n2\n", "Hexahedra\n1\n1 2 3 4 1 2 3 4 0\nTetrahedra\n2\n",
             "1 hexahedron beside 2 tetrahedra"},
        // Gmsh's quadratic tets under "Tetrahedra": was "unknown Medit section" far below.
        Edit{".mesh", "Tetrahedra\n2\n", "Tetrahedra\n1\n1 2 3 4 5 1 2 3 4 5 0\nTetrahedra\n2\n",
             ":12: a Tetrahedra line holds 11 numbers, not 5 (4 vertex indices and a reference): "
             "quadratic (10-node) tets"},
        Edit{".b64.vtu", "format=\"binary\">\n          ", "format=\"binary\">\n          !",
             "invalid base64"},
        Edit{".b64.vtu", "header_type=\"UInt64\"", "header_type=\"UInt32\"", "header says"},
        Edit{".b64.vtu", "type=\"Int32\" Name=\"connectivity\"",
             "type=\"String\" Name=\"connectivity\"", "expected a numeric type"},
        Edit{".asc.vtu", "<DataArray type=\"Int32\" Name=\"offsets\" format=\"ascii\">\n4",
             "<DataArray type=\"Int32\" Name=\"offsets\" format=\"ascii\">\n5",
             "tetrahedron with 5 points"},
        Edit{".asc.vtu", "Name=\"types\" format=\"ascii\">\n10",
             "Name=\"types\" format=\"ascii\">\n12", "1 hexahedron beside 1 tetrahedron"}),
    [](const ::testing::TestParamInfo<Edit>& info) {
      std::string name = info.param.extension.substr(1) + "_" + std::to_string(info.index);
      for (char& c : name) c = c == '.' ? '_' : c;
      return name;
    });

INSTANTIATE_TEST_SUITE_P(IoFormats, IoMeshMalformedTest,
                         ::testing::Values(".vtu", ".b64.vtu", ".asc.vtu", ".vtk", ".bin.vtk",
                                           ".msh", ".bin.msh", ".mesh", ".meshb"),
                         [](const ::testing::TestParamInfo<std::string>& info) {
                           std::string name = info.param.substr(1);
                           for (char& c : name) c = c == '.' ? '_' : c;
                           return name;
                         });

}  // namespace
}  // namespace tetrefine::io
