// Independent-reader check: files this library writes are read by meshio (Python), with the same
// point count, tet count and checksums of the coordinates, indices and "value" point data.
#include <array>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "absl/strings/str_cat.h"
#include "client/io/mesh_io.h"
#include "gtest/gtest.h"
#include "tests/io/io_test_util.h"

namespace tetrefine::io {
namespace {

using iotest::kPython;
using iotest::RandomMesh;
using iotest::RandomMeshOptions;
using iotest::ScratchDir;

// Runs `command` and returns its stdout and exit status.
std::pair<std::string, int> RunCommand(const std::string& command) {
  std::string out;
  FILE* pipe = popen(command.c_str(), "r");
  if (pipe == nullptr) return {"", -1};
  std::array<char, 4096> buffer;
  size_t n;
  while ((n = fread(buffer.data(), 1, buffer.size(), pipe)) > 0) out.append(buffer.data(), n);
  return {out, pclose(pipe)};
}

bool MeshioAvailable() {
  return RunCommand(std::string(kPython) + " -c 'import meshio' 2>/dev/null").second == 0;
}

// Passed to python3 -c (so it holds no single quote). Prints "points tets sum(points) sum(tet
// indices) sum(value)|none" for the file in argv[1].
constexpr char kScript[] = R"(
import sys, warnings
warnings.simplefilter("ignore")
import meshio, numpy as np
m = meshio.read(sys.argv[1])
tets = [c.data for c in m.cells if c.type == "tetra"]
t = np.concatenate(tets) if tets else np.zeros((0, 4), dtype=int)
v = m.point_data.get("value")
print(len(m.points), len(t), repr(float(np.sum(m.points))), int(np.sum(t)),
      "none" if v is None else repr(float(np.sum(v))))
)";

class IoMeshioTest : public ::testing::TestWithParam<std::string> {};

TEST_P(IoMeshioTest, MeshioReadsWhatWeWrite) {
  if (!MeshioAvailable()) GTEST_SKIP() << kPython << " cannot import meshio";
  ScratchDir dir;
  for (uint64_t seed : {1, 2, 3}) {
    SCOPED_TRACE(::testing::Message() << "seed " << seed << " format " << GetParam());
    RandomMeshOptions options;
    options.vertices = 30 + 17 * static_cast<int>(seed);
    options.tets = 50 + 23 * static_cast<int>(seed);
    const MeshFile mesh = RandomMesh(seed, options);
    const std::string path = dir.File("m" + GetParam());
    ASSERT_TRUE(WriteMesh(path, mesh).ok());
    const auto [out, status] =
        RunCommand(std::string(kPython) + " -c '" + kScript + "' " + path + " 2>&1");
    ASSERT_EQ(status, 0) << out;
    std::istringstream fields(out.substr(out.find_last_of('\n', out.size() - 2) + 1));
    size_t points = 0, tets = 0;
    double coordinate_sum = 0;
    long long index_sum = 0;
    std::string value_sum;
    fields >> points >> tets >> coordinate_sum >> index_sum >> value_sum;
    ASSERT_FALSE(fields.fail()) << out;
    EXPECT_EQ(points, mesh.mesh.points.size());
    EXPECT_EQ(tets, mesh.mesh.tets.size());
    double expected_coordinates = 0;
    for (const Vec3& p : mesh.mesh.points) expected_coordinates += p[0] + p[1] + p[2];
    long long expected_indices = 0;
    for (const Tet& t : mesh.mesh.tets) expected_indices += t[0] + t[1] + t[2] + t[3];
    // numpy sums pairwise, so allow rounding differences in the coordinate/value checksums.
    EXPECT_NEAR(coordinate_sum, expected_coordinates, 1e-9 * (1 + std::abs(expected_coordinates)));
    EXPECT_EQ(index_sum, expected_indices);
    if (GetParam() == ".mesh" || GetParam() == ".meshb") {
      EXPECT_EQ(value_sum, "none");  // Medit carries no vertex values
    } else {
      double expected_values = 0;
      for (double v : mesh.mesh.values) expected_values += v;
      ASSERT_NE(value_sum, "none") << out;
      EXPECT_NEAR(std::stod(value_sum), expected_values, 1e-9 * (1 + std::abs(expected_values)));
    }
  }
}

// meshio decodes a compressed appended .vtu array by array, renumbering offsets as it goes and
// finding each next array by its original offset: where a renumbered offset (a multiple of 4)
// equals a later original one it took the wrong array (1 refined mesh of 885 in a sweep). The
// writer keeps every offset but the first off multiples of 4; meshio reads each of many meshes
// of many sizes whole, in one Python process.
constexpr char kManyScript[] = R"(
import sys, warnings
warnings.simplefilter("ignore")
import meshio, numpy as np
for path in sys.argv[1:]:
    try:
        m = meshio.read(path)
        t = np.concatenate([c.data for c in m.cells if c.type == "tetra"])
        print(len(m.points), len(t), len(m.point_data["value"]), len(m.cell_data["quality"][0]))
    except Exception as e:
        print("error", type(e).__name__)
)";

TEST(IoMeshioVtu, NoOffsetCollidesWithMeshiosRenumbering) {
  ScratchDir dir;
  std::vector<std::string> paths;
  std::vector<std::pair<size_t, size_t>> sizes;
  for (uint64_t seed = 1; seed <= 400; ++seed) {
    RandomMeshOptions options;
    options.vertices = 4 + static_cast<int>(seed * 7 % 97);
    options.tets = 1 + static_cast<int>(seed * 13 % 151);
    options.labels = seed % 3 == 0;
    const MeshFile mesh = RandomMesh(seed, options);
    const std::string path = dir.File(absl::StrCat("m", seed, ".vtu"));
    ASSERT_TRUE(WriteMesh(path, mesh).ok());
    // Every offset but the first is off multiples of 4 (meshio's renumbered offsets are on them).
    const std::string text = iotest::ReadBytes(path);
    size_t arrays = 0;
    for (size_t at = text.find("offset=\""); at != std::string::npos;
         at = text.find("offset=\"", at + 1)) {
      const uint64_t offset = std::stoull(text.substr(at + 8));
      if (arrays++ > 0) {
        EXPECT_NE(offset % 4, 0u) << path << " offset " << offset;
      }
    }
    EXPECT_GE(arrays, 6u);
    paths.push_back(path);
    sizes.emplace_back(mesh.mesh.points.size(), mesh.mesh.tets.size());
  }
  if (!MeshioAvailable()) GTEST_SKIP() << kPython << " cannot import meshio";
  std::string command = std::string(kPython) + " -c '" + kManyScript + "'";
  for (const std::string& path : paths) command += " " + path;
  const auto [out, status] = RunCommand(command + " 2>&1");
  ASSERT_EQ(status, 0) << out;
  std::istringstream lines(out);
  for (size_t i = 0; i < paths.size(); ++i) {
    std::string line;
    ASSERT_TRUE(std::getline(lines, line)) << out;
    const auto [v, t] = sizes[i];
    EXPECT_EQ(line, absl::StrCat(v, " ", t, " ", v, " ", t)) << paths[i];
  }
}

// The other direction: meshio writes (its defaults: zlib-compressed binary .vtu, legacy VTK 5.1,
// Gmsh 4.1, Medit) and this library reads. Passed to python3 -c, so no single quotes.
constexpr char kWriteScript[] = R"(
import sys, warnings
warnings.simplefilter("ignore")
import meshio, numpy as np
rng = np.random.default_rng(4)
points = rng.uniform(-10, 10, (40, 3))
tets = np.array([rng.choice(40, 4, replace=False) for _ in range(70)])
tris = np.array([[0, 1, 2], [3, 4, 5]])
value = rng.uniform(-1, 1, 40)
kwargs = {}
if sys.argv[1].endswith(".msh"):
    kwargs = {"file_format": "gmsh", "binary": False}
elif sys.argv[1].endswith(".vtk"):
    kwargs = {"binary": False}
cells = [("tetra", tets)] if sys.argv[1].endswith(".msh") else [("triangle", tris), ("tetra", tets)]
meshio.write_points_cells(sys.argv[1], points, cells, point_data={"value": value}, **kwargs)
print(repr(float(points.sum())), int(tets.sum()), repr(float(value.sum())))
)";

TEST_P(IoMeshioTest, ReadsWhatMeshioWrites) {
  if (!MeshioAvailable()) GTEST_SKIP() << kPython << " cannot import meshio";
  ScratchDir dir;
  const std::string path = dir.File("from_meshio" + GetParam());
  const auto [out, status] =
      RunCommand(std::string(kPython) + " -c '" + kWriteScript + "' " + path + " 2>&1");
  ASSERT_EQ(status, 0) << out;
  std::istringstream fields(out.substr(out.find_last_of('\n', out.size() - 2) + 1));
  double coordinate_sum = 0, value_sum = 0;
  long long index_sum = 0;
  fields >> coordinate_sum >> index_sum >> value_sum;
  ASSERT_FALSE(fields.fail()) << out;
  absl::StatusOr<MeshFile> file = ReadMesh(path);
  ASSERT_TRUE(file.ok()) << file.status();
  EXPECT_EQ(file->mesh.points.size(), 40u);
  EXPECT_EQ(file->mesh.tets.size(), 70u);
  double coordinates = 0;
  for (const Vec3& p : file->mesh.points) coordinates += p[0] + p[1] + p[2];
  long long indices = 0;
  for (const Tet& t : file->mesh.tets) indices += t[0] + t[1] + t[2] + t[3];
  EXPECT_NEAR(coordinates, coordinate_sum, 1e-9);
  EXPECT_EQ(indices, index_sum);
  if (GetParam() != ".mesh" && GetParam() != ".meshb") {
    ASSERT_EQ(file->mesh.values.size(), 40u);
    double values = 0;
    for (double v : file->mesh.values) values += v;
    EXPECT_NEAR(values, value_sum, 1e-9);
  }
}

INSTANTIATE_TEST_SUITE_P(IoFormats, IoMeshioTest,
                         ::testing::Values(".vtu", ".vtk", ".msh", ".mesh", ".meshb"));

}  // namespace
}  // namespace tetrefine::io
