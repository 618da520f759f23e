// Independent readers: what this library writes, in every format and variant, is read by meshio,
// VTK 9 (python3-vtk9, what ParaView and 3D Slicer are built on) and Gmsh itself, with the same
// tets, the labels in order under the expected name, and the frame tag. Each check is skipped
// when its tool is not installed (scripts/install-deps.sh installs them all).
#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <ostream>
#include <sstream>
#include <string>
#include <vector>

#include "absl/strings/str_cat.h"
#include "client/io/mesh_io.h"
#include "gtest/gtest.h"
#include "tests/io/io_test_util.h"
#include "tests/support/child_process.h"

namespace tetrefine::io {
namespace {

using iotest::kPython;
using iotest::RandomMesh;
using iotest::RandomMeshOptions;
using iotest::ScratchDir;

constexpr char kGmsh[] = "/usr/bin/gmsh";

// Runs `argv` to completion (tests/support's RunProcess): exit code and stdout followed by stderr.
std::pair<std::string, int> RunTool(const std::vector<std::string>& argv) {
  const testing::ProcessResult result = testing::RunProcess(argv);
  return {result.out + result.err, result.exit_code};
}

bool PythonImports(const std::string& module) {
  return std::filesystem::exists(kPython) &&
         RunTool({kPython, "-c", absl::StrCat("import ", module)}).second == 0;
}

// What a reader reported: counts and checksums. Labels are summed plainly and weighted by
// position (sum of (i + 1) * label over tets), so a reordering shows.
struct Report {
  long long points = -1;
  long long tets = -1;
  long long index_sum = -1;
  double coordinate_sum = 0;
  long long label_count = -1;
  long long label_sum = 0;
  long long label_weighted = 0;
  std::string space;  // frame tag the reader saw, "-" for none
};

Report Expected(const MeshFile& file, bool negate_xy) {
  Report r;
  r.points = static_cast<long long>(file.mesh.points.size());
  r.tets = static_cast<long long>(file.mesh.tets.size());
  r.index_sum = 0;
  for (const Tet& t : file.mesh.tets) r.index_sum += t[0] + t[1] + t[2] + t[3];
  for (const Vec3& p : file.mesh.points) {
    r.coordinate_sum += (negate_xy ? -p[0] - p[1] : p[0] + p[1]) + p[2];
  }
  r.label_count = static_cast<long long>(file.mesh.labels.size());
  for (size_t i = 0; i < file.mesh.labels.size(); ++i) {
    r.label_sum += file.mesh.labels[i];
    r.label_weighted += static_cast<long long>(i + 1) * file.mesh.labels[i];
  }
  return r;
}

// Runs `script` on `path` with one extra argument; parses the last line it prints.
Report RunReader(const std::string& script, const std::string& path, const std::string& arg) {
  const testing::ProcessResult run = testing::RunProcess({kPython, "-c", script, path, arg});
  const std::string& out = run.out;
  EXPECT_EQ(run.exit_code, 0) << out << run.err;
  const size_t start = out.find_last_of('\n', out.size() - 2);
  std::istringstream fields(start == std::string::npos ? out : out.substr(start + 1));
  Report r;
  fields >> r.points >> r.tets >> r.index_sum >> r.coordinate_sum >> r.label_count >> r.label_sum >>
      r.label_weighted >> r.space;
  EXPECT_FALSE(fields.fail()) << out << run.err;
  return r;
}

// `check_order`: whether the reader must see the tets in our order. Gmsh files group elements by
// entity, one per physical group, so other readers see a .msh's tets grouped by label.
void ExpectReport(const Report& got, const Report& want, bool check_space,
                  bool check_order = true) {
  EXPECT_EQ(got.points, want.points);
  EXPECT_EQ(got.tets, want.tets);
  EXPECT_EQ(got.index_sum, want.index_sum);
  EXPECT_NEAR(got.coordinate_sum, want.coordinate_sum, 1e-9 * (1 + std::abs(want.coordinate_sum)));
  EXPECT_EQ(got.label_count, want.label_count);
  EXPECT_EQ(got.label_sum, want.label_sum);
  if (check_order) {
    EXPECT_EQ(got.label_weighted, want.label_weighted);
  }
  if (check_space) {
    EXPECT_EQ(got.space, want.space);
  }
}

constexpr char kMeshioScript[] = R"(
import sys, warnings
warnings.simplefilter("ignore")
import meshio, numpy as np
m = meshio.read(sys.argv[1])
key = sys.argv[2]
tets, labels = [], []
for i, c in enumerate(m.cells):
    if c.type == "tetra":
        tets.append(c.data)
        if key in m.cell_data:
            labels.append(np.asarray(m.cell_data[key][i]).astype(np.int64).reshape(-1))
t = np.concatenate(tets)
l = np.concatenate(labels) if labels else np.zeros(0, dtype=np.int64)
w = int(np.sum(l * np.arange(1, len(l) + 1))) if len(l) else 0
print(len(m.points), len(t), int(t.sum()), repr(float(m.points.sum())), len(l), int(l.sum()), w, "-")
)";

constexpr char kVtkScript[] = R"(
import sys
import vtk
from vtk.util.numpy_support import vtk_to_numpy
path, key = sys.argv[1], sys.argv[2]
if path.endswith(".vtu"):
    r = vtk.vtkXMLUnstructuredGridReader()
else:
    # VTK's defaults, as a user's script has them: no ReadAllScalarsOn or ReadAllFieldsOn.
    r = vtk.vtkUnstructuredGridReader()
r.SetFileName(path)
r.Update()
g = r.GetOutput()
types = vtk_to_numpy(g.GetCellTypesArray())
conn = vtk_to_numpy(g.GetCells().GetConnectivityArray()).astype("int64")
pts = vtk_to_numpy(g.GetPoints().GetData())
a = g.GetCellData().GetArray(key)
l = vtk_to_numpy(a).astype("int64") if a is not None else conn[:0]
w = int((l * (1 + vtk.util.numpy_support.numpy.arange(len(l)))).sum())
space = "-"
f = g.GetFieldData().GetAbstractArray("SPACE")
if f is not None:
    space = f.GetValue(0)
elif not path.endswith(".vtu") and "SPACE=" in r.GetHeader():
    space = r.GetHeader().split("SPACE=")[1][:3]
assert (types == 10).all()
print(g.GetNumberOfPoints(), g.GetNumberOfCells(), int(conn.sum()), repr(float(pts.sum())),
      len(l), int(l.sum()), w, space)
)";

MeshFile TestMesh(uint64_t seed, MeshFrame frame, const std::string& label_name) {
  RandomMeshOptions options;
  options.vertices = 60;
  options.tets = 90;
  options.labels = true;
  options.label_name = label_name;
  options.frame = frame;
  MeshFile mesh = RandomMesh(seed, options);
  // Region numbers from -2 to 3: zero and negative labels beside positive ones, which every
  // format must store as they are (meshio refused our .msh for such a mix until 2026-11-25).
  for (size_t i = 0; i < mesh.mesh.labels.size(); ++i) {
    mesh.mesh.labels[i] = static_cast<int32_t>((i * 7 + seed) % 6) - 2;
  }
  return mesh;
}

struct Case {
  std::string name;
  std::string extension;
  MeshWriteOptions options;
};

// By name in test names: GoogleTest would print the struct's bytes, and ctest appends them.
void PrintTo(const Case& c, std::ostream* os) { *os << c.name; }

std::vector<Case> Cases() {
  using Layout = VtuWriteOptions::Layout;
  std::vector<Case> all = {
      {"vtk_ascii", ".vtk", {}},  {"vtk_binary", ".vtk", {.binary = true}},
      {"msh_ascii", ".msh", {}},  {"msh_binary", ".msh", {.binary = true}},
      {"mesh", ".mesh", {}},      {"meshb_v2", ".meshb", {.meshb_version = 2}},
      {"meshb_v3", ".meshb", {}}, {"meshb_v4", ".meshb", {.meshb_version = 4}}};
  for (Layout layout : {Layout::kAppendedRaw, Layout::kInlineBase64, Layout::kAscii}) {
    for (VtkCompressor c :
         {VtkCompressor::kNone, VtkCompressor::kZlib, VtkCompressor::kLzma, VtkCompressor::kLz4}) {
      if (layout == Layout::kAscii && c != VtkCompressor::kNone) continue;
      Case k{absl::StrCat("vtu_", static_cast<int>(layout), "_", static_cast<int>(c)), ".vtu", {}};
      k.options.vtu.layout = layout;
      k.options.vtu.compressor = c;
      k.options.vtu.block_size = 1024;
      all.push_back(k);
    }
  }
  return all;
}

class IoIndependentReaderTest : public ::testing::TestWithParam<Case> {};

TEST_P(IoIndependentReaderTest, MeshioReadsLabels) {
  if (!PythonImports("meshio")) GTEST_SKIP() << "python3-meshio is not installed";
  const Case& c = GetParam();
  // meshio's VTU reader does not take lz4 (it knows zlib and lzma only).
  if (c.extension == ".vtu" && c.options.vtu.compressor == VtkCompressor::kLz4) {
    GTEST_SKIP() << "meshio does not read lz4-compressed VTU";
  }
  ScratchDir dir;
  const std::string path = dir.File("m" + c.extension);
  const std::string key = c.extension == ".msh"                               ? "gmsh:physical"
                          : c.extension == ".mesh" || c.extension == ".meshb" ? "medit:ref"
                                                                              : "region";
  const MeshFile mesh = TestMesh(5, MeshFrame::kUntagged, "region");
  ASSERT_TRUE(WriteMesh(path, mesh, c.options).ok());
  ExpectReport(RunReader(kMeshioScript, path, key), Expected(mesh, false), false,
               c.extension != ".msh");
}

TEST_P(IoIndependentReaderTest, VtkReadsLabelsAndFrame) {
  const Case& c = GetParam();
  if (c.extension != ".vtu" && c.extension != ".vtk") GTEST_SKIP() << "not a VTK format";
  if (!PythonImports("vtk")) GTEST_SKIP() << "python3-vtk9 is not installed";
  ScratchDir dir;
  const std::string path = dir.File("m" + c.extension);
  for (MeshFrame frame : {MeshFrame::kUntagged, MeshFrame::kLps, MeshFrame::kRas}) {
    SCOPED_TRACE(static_cast<int>(frame));
    const MeshFile mesh = TestMesh(7, frame, "CellEntityIds");
    ASSERT_TRUE(WriteMesh(path, mesh, c.options).ok());
    Report want = Expected(mesh, frame == MeshFrame::kLps);
    want.space = frame == MeshFrame::kUntagged ? "-" : std::string(FrameTag(frame));
    ExpectReport(RunReader(kVtkScript, path, "CellEntityIds"), want, true);
  }
}

INSTANTIATE_TEST_SUITE_P(IoFormats, IoIndependentReaderTest, ::testing::ValuesIn(Cases()),
                         [](const ::testing::TestParamInfo<Case>& info) {
                           return info.param.name;
                         });

// meshio takes $ElementData entries in the order of the elements, which a .msh groups by label:
// each tet's quality and iteration must come with that tet (sum over tets of the value times
// (1 + the sum of its vertex indices), which a misplaced value changes).
constexpr char kMeshioElementDataScript[] = R"(
import sys, warnings
warnings.simplefilter("ignore")
import meshio, numpy as np
m = meshio.read(sys.argv[1])
sums = []
for key in ("quality", "iteration"):
    s = 0.0
    for i, c in enumerate(m.cells):
        if c.type == "tetra":
            v = np.asarray(m.cell_data[key][i], dtype=np.float64).reshape(-1)
            s += float(np.sum(v * (1 + c.data.sum(axis=1))))
    sums.append(repr(s))
print(" ".join(sums))
)";

TEST(IoIndependentReaderTest, MeshioPairsMshElementDataWithItsTets) {
  if (!PythonImports("meshio")) GTEST_SKIP() << "python3-meshio is not installed";
  ScratchDir dir;
  const MeshFile mesh = TestMesh(11, MeshFrame::kUntagged, "gmsh:physical");
  ASSERT_FALSE(mesh.tet_quality.empty());
  ASSERT_FALSE(mesh.tet_iteration.empty());
  double quality = 0.0, iteration = 0.0;
  for (size_t i = 0; i < mesh.mesh.tets.size(); ++i) {
    const Tet& t = mesh.mesh.tets[i];
    const double weight = 1.0 + t[0] + t[1] + t[2] + t[3];
    quality += static_cast<double>(mesh.tet_quality[i]) * weight;
    iteration += static_cast<double>(mesh.tet_iteration[i]) * weight;
  }
  for (bool binary : {false, true}) {
    SCOPED_TRACE(binary ? "binary" : "ascii");
    const std::string path = dir.File("m.msh");
    ASSERT_TRUE(WriteMesh(path, mesh, {.binary = binary}).ok());
    const testing::ProcessResult run =
        testing::RunProcess({kPython, "-c", kMeshioElementDataScript, path});
    ASSERT_EQ(run.exit_code, 0) << run.out << run.err;
    std::istringstream fields(run.out);
    double got_quality = 0.0, got_iteration = 0.0;
    fields >> got_quality >> got_iteration;
    ASSERT_FALSE(fields.fail()) << run.out;
    EXPECT_NEAR(got_quality, quality, 1e-9 * std::abs(quality));
    EXPECT_NEAR(got_iteration, iteration, 1e-9 * std::abs(iteration));
  }
}

// Each tet as its sorted corner coordinates with its label, sorted: what a mesh is regardless
// of vertex and tet numbering.
std::vector<std::pair<std::array<Vec3, 4>, int32_t>> TetsWithLabels(const MeshFile& file) {
  std::vector<std::pair<std::array<Vec3, 4>, int32_t>> out;
  for (size_t t = 0; t < file.mesh.tets.size(); ++t) {
    std::array<Vec3, 4> corners;
    for (int k = 0; k < 4; ++k) corners[k] = file.mesh.points[file.mesh.tets[t][k]];
    std::sort(corners.begin(), corners.end());
    out.emplace_back(corners, file.mesh.labels[t]);
  }
  std::sort(out.begin(), out.end());
  return out;
}

// Gmsh itself opens what we write (ASCII and binary 4.1 with physical groups) and saves it again
// as binary MSH 2.2 (binary, so the coordinates come back to the bit); reading that back gives
// the same tets with the same labels.
TEST(IoIndependentReaderTest, GmshResavesOurMsh) {
  if (!std::filesystem::exists(kGmsh) || RunTool({kGmsh, "--version"}).second != 0) {
    GTEST_SKIP() << "gmsh is not installed";
  }
  ScratchDir dir;
  for (bool binary : {false, true}) {
    SCOPED_TRACE(binary ? "binary" : "ascii");
    MeshFile mesh = TestMesh(9, MeshFrame::kUntagged, "gmsh:physical");
    // Gmsh reads a negative physical tag as the group of its absolute value with the entity's
    // orientation reversed, and saves it so: zero and positive labels only here.
    for (int32_t& label : mesh.mesh.labels) label = std::abs(label);
    const std::string in = dir.File("ours.msh");
    const std::string out = dir.File("resaved.msh");
    ASSERT_TRUE(WriteMesh(in, mesh, {.binary = binary}).ok());
    const auto [log, status] =
        RunTool({kGmsh, in, "-save", "-format", "msh22", "-bin", "-o", out, "-nt", "1"});
    ASSERT_EQ(status, 0) << log;
    absl::StatusOr<MeshFile> back = ReadMesh(out);
    ASSERT_TRUE(back.ok()) << back.status();
    EXPECT_EQ(back->label_name, "gmsh:physical");
    // Gmsh renumbers elements by entity, so compare (tet corners, label) as sets.
    EXPECT_EQ(TetsWithLabels(*back), TetsWithLabels(mesh));
  }
}

// Gmsh's MSH 2 writer lists every element of a volume in two physical groups twice, once per
// group (an outside review, 2026-11-28: `info` said 2,264 tets, twice the volume and no boundary
// for a mesh of 1,132). Read as Gmsh 4's file of the same mesh reads: each tet once, labelled by
// its volume's first group, the second group named as not read.
TEST(IoIndependentReaderTest, GmshTwoFilesOfAVolumeInTwoGroupsReadAlike) {
  if (!std::filesystem::exists(kGmsh) || RunTool({kGmsh, "--version"}).second != 0) {
    GTEST_SKIP() << "gmsh is not installed";
  }
  ScratchDir dir;
  const std::string geo = dir.File("box.geo");
  iotest::WriteBytes(geo,
                     "SetFactory(\"OpenCASCADE\");\nBox(1) = {0, 0, 0, 10, 10, 10};\n"
                     "Physical Volume(\"a\", 1) = {1};\nPhysical Volume(\"b\", 2) = {1};\n"
                     "Mesh.MeshSizeMax = 4;\n");
  std::vector<std::pair<std::string, MeshFile>> files;
  for (const char* format : {"msh41", "msh22"}) {
    for (bool binary : {false, true}) {
      const std::string out = dir.File(absl::StrCat(format, binary ? "_bin" : "", ".msh"));
      std::vector<std::string> argv = {kGmsh, "-3", geo, "-format", format, "-o", out, "-nt", "1"};
      if (binary) argv.push_back("-bin");
      const auto [log, status] = RunTool(argv);
      ASSERT_EQ(status, 0) << log;
      absl::StatusOr<MeshFile> file = ReadMesh(out);
      ASSERT_TRUE(file.ok()) << out << ": " << file.status();
      files.emplace_back(out, *std::move(file));
    }
  }
  for (size_t i = 0; i < files.size(); ++i) {
    const auto& [path, file] = files[i];
    SCOPED_TRACE(path);
    // ASCII files print 16 digits: each compared with the MSH 4 file of its own encoding.
    EXPECT_EQ(TetsWithLabels(file), TetsWithLabels(files[i % 2].second));
    double volume = 0.0;
    for (const Tet& t : file.mesh.tets) {
      const auto& p = file.mesh.points;
      volume += std::abs(SignedVolume6(p[t[0]], p[t[1]], p[t[2]], p[t[3]])) / 6;
    }
    EXPECT_NEAR(volume, 1000.0, 1e-9);
    EXPECT_TRUE(std::all_of(file.mesh.labels.begin(), file.mesh.labels.end(),
                            [](int32_t l) { return l == 1; }));
    EXPECT_EQ(file.dropped_arrays,
              std::vector<std::string>{"physical group 2 (\"b\") of volume 1 (a tet keeps one "
                                       "label: its volume's first physical group)"});
  }
}

}  // namespace
}  // namespace tetrefine::io
