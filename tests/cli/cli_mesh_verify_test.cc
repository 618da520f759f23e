// `tetrefine mesh`, `verify` and `info` on generated files.

#include <algorithm>
#include <string>
#include <vector>

#include "absl/strings/match.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "client/io/mesh_io.h"
#include "core/mesh_validation.h"
#include "gtest/gtest.h"
#include "tests/cli/cli_test_util.h"
#include "tests/io/io_test_util.h"
#include "tests/support/geometry.h"

namespace tetrefine::clitest {
namespace {

using io::iotest::ScratchDir;

class CliMeshVerify : public ::testing::Test {
 protected:
  void SetUp() override {
    volume_ = dir_.File("bump.nii");
    WriteVolume(volume_, BumpVolume({11, 9, 7}, {-5.0, 0.0, 10.0}, {1.0, 1.5, 2.0}));
  }

  // `tetrefine mesh` into `name`; returns the mesh it wrote.
  io::MeshFile MakeMesh(const std::string& name, const std::vector<std::string>& flags) {
    std::vector<std::string> args = {"mesh", "--volume", volume_, "--output", dir_.File(name)};
    args.insert(args.end(), flags.begin(), flags.end());
    const ProcessResult run = RunTetrefine(args);
    EXPECT_EQ(run.exit_code, 0) << run.err;
    absl::StatusOr<io::MeshFile> mesh = io::ReadMesh(dir_.File(name));
    EXPECT_TRUE(mesh.ok()) << mesh.status();
    return mesh.ok() ? *mesh : io::MeshFile{};
  }

  ProcessResult Verify(const std::string& mesh, const std::vector<std::string>& flags = {}) {
    std::vector<std::string> args = {"verify", "--volume", volume_, "--mesh", mesh};
    args.insert(args.end(), flags.begin(), flags.end());
    return RunTetrefine(args);
  }

  ScratchDir dir_;
  std::string volume_;
};

TEST_F(CliMeshVerify, MeshThenVerifyRoundTrip) {
  const io::MeshFile mesh = MakeMesh("grid.vtu", {"--block", "3"});
  // 10 x 8 x 6 voxels in blocks of 3: 4 x 3 x 2 cells (the last ones thinner).
  EXPECT_EQ(mesh.mesh.tets.size(), 5u * 4 * 3 * 2);
  EXPECT_EQ(mesh.mesh.values.size(), mesh.mesh.points.size());
  EXPECT_TRUE(CheckFaces(mesh.mesh.points, mesh.mesh.tets).ok());
  const ProcessResult run = Verify(dir_.File("grid.vtu"), {"--epsilon", "0.05"});
  EXPECT_EQ(run.exit_code, 0) << run.err << run.out;
  EXPECT_EQ(run.err, "");
  for (const char* text :
       {"valid", "total volume", "1440 mm^3", "boundary area", "discrepancy", "above epsilon 0.05",
        "values resampled from the volume", "quality (mean ratio)"}) {
    EXPECT_TRUE(absl::StrContains(run.out, text)) << text << " missing from\n" << run.out;
  }
}

// The lattice line says whether it covers every tet or a sample (verify checks a sample of
// 200 000 tets of a larger mesh; its line read as the whole mesh's, an outside review found).
TEST_F(CliMeshVerify, TheLatticeLineSaysWhenItIsASample) {
  MakeMesh("grid.vtu", {"--block", "3"});
  const ProcessResult every = Verify(dir_.File("grid.vtu"));
  EXPECT_TRUE(absl::StrContains(every.out, "points in every one of the 120 tets")) << every.out;
  io::MeshFile big;
  big.mesh = testing::FiveTetMesh({-4.5, 0.5, 10.5}, {4.5, 11.5, 21.5}, {35, 35, 35});
  ASSERT_GT(big.mesh.tets.size(), 200000u);
  ASSERT_TRUE(io::WriteMesh(dir_.File("big.vtu"), big).ok());
  const ProcessResult sampled = Verify(dir_.File("big.vtu"));
  EXPECT_TRUE(absl::StrContains(
      sampled.out, absl::StrCat("points in a sample of 200000 of the ", big.mesh.tets.size(),
                                " tets (its max can be below the mesh's)")))
      << sampled.out << sampled.err;
}

TEST_F(CliMeshVerify, MaskThresholdMeshesFewerCells) {
  const io::MeshFile all = MakeMesh("all.mesh", {});
  const io::MeshFile masked = MakeMesh("masked.mesh", {"--mask-threshold", "40"});
  EXPECT_EQ(all.mesh.tets.size(), 5u * 10 * 8 * 6);
  EXPECT_GT(masked.mesh.tets.size(), 0u);
  EXPECT_LT(masked.mesh.tets.size(), all.mesh.tets.size());
  EXPECT_LT(masked.mesh.points.size(), all.mesh.points.size());
  EXPECT_EQ(Verify(dir_.File("masked.mesh")).exit_code, 0);
  const ProcessResult none = RunTetrefine(
      {"mesh", "--volume", volume_, "--mask-threshold", "1e9", "--output", dir_.File("none.vtu")});
  EXPECT_EQ(none.exit_code, 2);
  EXPECT_TRUE(absl::StrContains(none.err, "no cell")) << none.err;
  EXPECT_FALSE(FileExists(dir_.File("none.vtu")));
}

TEST_F(CliMeshVerify, RefinedMeshVerifies) {
  MakeMesh("coarse.vtu", {"--block", "4"});
  const ProcessResult refine =
      RunTetrefine({"refine", "--volume", volume_, "--mesh", dir_.File("coarse.vtu"), "--epsilon",
                    "0.05", "--output", dir_.File("fine.vtu"), "--quiet"});
  ASSERT_EQ(refine.exit_code, 0) << refine.err;
  EXPECT_EQ(Verify(dir_.File("fine.vtu")).exit_code, 0);
}

TEST_F(CliMeshVerify, InvertedTetIsNotValid) {
  io::MeshFile mesh = MakeMesh("grid.vtu", {"--block", "3"});
  std::swap(mesh.mesh.tets[7][0], mesh.mesh.tets[7][1]);
  ASSERT_TRUE(io::WriteMesh(dir_.File("inverted.vtu"), mesh).ok());
  const ProcessResult run = Verify(dir_.File("inverted.vtu"));
  EXPECT_EQ(run.exit_code, 1);
  ASSERT_EQ(SplitLines(run.err).size(), 1u) << run.err;
  EXPECT_TRUE(absl::StrContains(run.err, dir_.File("inverted.vtu"))) << run.err;
  // Where it is, not only its number: its vertices and their coordinates.
  const Tet& t = mesh.mesh.tets[7];
  const Vec3& p = mesh.mesh.points[t[0]];
  EXPECT_TRUE(absl::StrContains(
      run.err, absl::StrFormat("1 inverted tets (first: tet 7: vertices %u (%g, %g, %g), %u (",
                               t[0], p[0], p[1], p[2], t[1])))
      << run.err;
  EXPECT_TRUE(absl::StrContains(run.out, "NOT VALID")) << run.out;
}

TEST_F(CliMeshVerify, DegenerateTetsAndOutsideVerticesAreLocated) {
  io::MeshFile mesh = MakeMesh("grid.vtu", {"--block", "3"});
  // A flat tet on three vertices of tet 0 and their centroid.
  const Tet t0 = mesh.mesh.tets[0];
  Vec3 c{};
  for (int k = 0; k < 3; ++k) {
    for (int a = 0; a < 3; ++a) c[a] += mesh.mesh.points[t0[k]][a] / 3.0;
  }
  mesh.mesh.points.push_back(c);
  mesh.mesh.values.push_back(0.0);
  const uint32_t flat_vertex = static_cast<uint32_t>(mesh.mesh.points.size() - 1);
  mesh.mesh.tets.push_back({t0[0], t0[1], t0[2], flat_vertex});
  ASSERT_TRUE(io::WriteMesh(dir_.File("flat.vtu"), mesh).ok());
  const ProcessResult flat = Verify(dir_.File("flat.vtu"));
  EXPECT_EQ(flat.exit_code, 1) << flat.out;
  EXPECT_TRUE(absl::StrContains(flat.err, absl::StrCat("1 degenerate tets (first: tet ",
                                                       mesh.mesh.tets.size() - 1, ": vertices ")))
      << flat.err;

  io::MeshFile moved = MakeMesh("grid.vtu", {"--block", "3"});
  moved.mesh.points[5][0] += 1000.0;
  ASSERT_TRUE(io::WriteMesh(dir_.File("moved.vtu"), moved).ok());
  const ProcessResult out = Verify(dir_.File("moved.vtu"));
  EXPECT_EQ(out.exit_code, 1) << out.out;
  const Vec3& p = moved.mesh.points[5];
  EXPECT_TRUE(absl::StrContains(out.err, absl::StrFormat("1 vertices outside the volume (first: "
                                                         "vertex 5 at (%g, %g, %g) mm; the volume "
                                                         "spans [",
                                                         p[0], p[1], p[2])))
      << out.err;
}

TEST_F(CliMeshVerify, FaceInThreeTetsIsNotValid) {
  io::MeshFile mesh;
  mesh.mesh.points = {{-2, 2, 14},     {0, 2, 14},      {-2, 4, 14},
                      {-1.5, 2.5, 12}, {-1.5, 2.5, 16}, {-1.4, 2.4, 18}};
  mesh.mesh.tets = {{0, 1, 2, 4}, {0, 2, 1, 3}, {0, 1, 2, 5}};
  ASSERT_TRUE(io::WriteMesh(dir_.File("triple.vtu"), mesh).ok());
  const ProcessResult run = Verify(dir_.File("triple.vtu"));
  EXPECT_EQ(run.exit_code, 1) << run.out;
  ASSERT_EQ(SplitLines(run.err).size(), 1u) << run.err;
  EXPECT_TRUE(absl::StrContains(run.err, "shared by 3 tets")) << run.err;
}

TEST_F(CliMeshVerify, DuplicateVerticesAreNotValid) {
  io::MeshFile mesh = MakeMesh("grid.vtu", {"--block", "3"});
  // A crack: tet 0 uses a copy of its first vertex instead of the shared one.
  mesh.mesh.points.push_back(mesh.mesh.points[mesh.mesh.tets[0][0]]);
  mesh.mesh.values.push_back(mesh.mesh.values[mesh.mesh.tets[0][0]]);
  mesh.mesh.tets[0][0] = static_cast<uint32_t>(mesh.mesh.points.size() - 1);
  ASSERT_TRUE(io::WriteMesh(dir_.File("crack.vtu"), mesh).ok());
  const ProcessResult run = Verify(dir_.File("crack.vtu"));
  EXPECT_EQ(run.exit_code, 1) << run.out;
  EXPECT_TRUE(absl::StrContains(run.err, "duplicate vertices")) << run.err;
}

// A hanging node: one tet split in two at the midpoint of an edge another tet shares, that tet
// left whole. The face check alone passes it; verify and refine name the vertex and the file.
TEST_F(CliMeshVerify, HangingNodeIsNotValidAndRefineRefusesIt) {
  io::MeshFile mesh = MakeMesh("grid.vtu", {"--block", "3"});
  Mesh& m = mesh.mesh;
  auto tets_on_edge = [&](uint32_t u, uint32_t v) {
    return std::count_if(m.tets.begin(), m.tets.end(), [&](const Tet& t) {
      return std::find(t.begin(), t.end(), u) != t.end() &&
             std::find(t.begin(), t.end(), v) != t.end();
    });
  };
  size_t t = 0;
  while (tets_on_edge(m.tets[t][0], m.tets[t][1]) < 2) ++t;
  const Tet tet = m.tets[t];
  const Vec3& a = m.points[tet[0]];
  const Vec3& b = m.points[tet[1]];
  const auto mid = static_cast<uint32_t>(m.points.size());
  m.points.push_back({0.5 * (a[0] + b[0]), 0.5 * (a[1] + b[1]), 0.5 * (a[2] + b[2])});
  m.values.push_back(0.5 * (m.values[tet[0]] + m.values[tet[1]]));
  m.tets[t] = {mid, tet[1], tet[2], tet[3]};
  m.tets.push_back({tet[0], mid, tet[2], tet[3]});
  ASSERT_TRUE(CheckFaces(m.points, m.tets).ok());
  const std::string path = dir_.File("hanging.vtu");
  ASSERT_TRUE(io::WriteMesh(path, mesh).ok());
  const std::string problem = absl::StrCat("mesh is not conformal: vertex ", mid, " at ");

  const ProcessResult verify = Verify(path);
  EXPECT_EQ(verify.exit_code, 1) << verify.out;
  ASSERT_EQ(SplitLines(verify.err).size(), 1u) << verify.err;
  EXPECT_TRUE(absl::StrContains(verify.err, path)) << verify.err;
  EXPECT_TRUE(absl::StrContains(verify.err, problem)) << verify.err;
  EXPECT_TRUE(absl::StrContains(verify.out, problem)) << verify.out;
  EXPECT_TRUE(absl::StrContains(verify.out, "NOT VALID")) << verify.out;

  const ProcessResult refine =
      RunTetrefine({"refine", "--volume", volume_, "--mesh", path, "--epsilon", "0.05", "--output",
                    dir_.File("out.vtu"), "--quiet"});
  EXPECT_EQ(refine.exit_code, 2) << refine.out;
  EXPECT_TRUE(absl::StrContains(refine.err, path)) << refine.err;
  EXPECT_TRUE(absl::StrContains(refine.err, problem)) << refine.err;
  EXPECT_FALSE(FileExists(dir_.File("out.vtu")));
}

TEST_F(CliMeshVerify, VerticesOutsideNeedClamp) {
  io::MeshFile mesh = MakeMesh("grid.vtu", {"--block", "3"});
  for (Vec3& p : mesh.mesh.points) p[2] += 1.0;  // the top layer leaves the volume
  ASSERT_TRUE(io::WriteMesh(dir_.File("shifted.vtu"), mesh).ok());
  const ProcessResult strict = Verify(dir_.File("shifted.vtu"));
  EXPECT_EQ(strict.exit_code, 1);
  EXPECT_TRUE(absl::StrContains(strict.err, "outside the volume")) << strict.err;
  EXPECT_EQ(Verify(dir_.File("shifted.vtu"), {"--clamp"}).exit_code, 0);
}

// A valid mesh scaled by 1e80 made verify abort (std::length_error in the overlap check, found by
// a sweep, 2026-11-28): it is an invalid mesh, said so as refine says it.
TEST_F(CliMeshVerify, HugeCoordinatesAreNamedNotACrash) {
  io::MeshFile mesh = MakeMesh("grid.vtu", {"--block", "3"});
  for (Vec3& p : mesh.mesh.points) {
    for (double& x : p) x *= 1e80;
  }
  ASSERT_TRUE(io::WriteMesh(dir_.File("huge.vtu"), mesh).ok());
  const ProcessResult run = Verify(dir_.File("huge.vtu"), {"--clamp"});
  EXPECT_EQ(run.exit_code, 1) << run.out << run.err;
  EXPECT_TRUE(absl::StrContains(run.out + run.err, "is too large: coordinates must lie within"))
      << run.out << run.err;
  // info describes the file without overflowing figures ("volume inf", "mean -nan" before).
  const ProcessResult info = RunTetrefine({"info", dir_.File("huge.vtu")});
  EXPECT_EQ(info.exit_code, 0) << info.err;
  EXPECT_TRUE(absl::StrContains(info.out, "not measured: mesh.points[")) << info.out;
  EXPECT_TRUE(absl::StrContains(info.out, "is too large: coordinates must lie within")) << info.out;
  for (const char* overflow : {"inf", "nan", "volume"}) {
    EXPECT_FALSE(absl::StrContains(info.out, overflow)) << overflow << " in\n" << info.out;
  }
}

TEST_F(CliMeshVerify, InfoOnAVolume) {
  const ProcessResult run = RunTetrefine({"info", volume_});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  for (const char* text :
       {"11 x 9 x 7 (693 voxels)", "float64", "1 x 1.5 x 2 mm", "(-5, 0, 10) mm, world RAS",
        "[-5, 5] x [0, 12] x [10, 22]", "value range", "file affine (RAS)", "warnings"}) {
    EXPECT_TRUE(absl::StrContains(run.out, text)) << text << " missing from\n" << run.out;
  }
  // An LPS NRRD: its affine shown in RAS negates x and y, and the negated zeros print as 0, not
  // as -0 (a file-format sweep saw "-0" entries).
  const std::string nrrd = dir_.File("lps.nrrd");
  std::string bytes =
      "NRRD0004\ntype: uint8\ndimension: 3\nspace: left-posterior-superior\nsizes: 2 2 2\n"
      "space directions: (1,0,0) (0,1,0) (0,0,1)\nspace origin: (0,0,0)\nencoding: raw\n\n";
  bytes.append(8, '\1');
  io::iotest::WriteBytes(nrrd, bytes);
  const ProcessResult lps = RunTetrefine({"info", nrrd});
  ASSERT_EQ(lps.exit_code, 0) << lps.err;
  EXPECT_FALSE(absl::StrContains(lps.out, "-0 ")) << lps.out;
  EXPECT_FALSE(absl::StrContains(lps.out, "-0]")) << lps.out;
  // The origin too: an outside review saw "origin (-0, -254, 0)" for the T1 volume (its affine
  // has -0 in x, and its axes are swapped and flipped).
  const ProcessResult t1 = RunTetrefine(
      {"info", std::string(TETREFINE_SHARED_DATA_DIR) + "/t1_brain_128x128x62.nii.gz"});
  ASSERT_EQ(t1.exit_code, 0) << t1.err;
  EXPECT_TRUE(absl::StrContains(t1.out, "origin             (0, -254, 0) mm, world RAS")) << t1.out;
  EXPECT_TRUE(absl::StrContains(lps.out, "file affine (RAS)  [          -1            0"))
      << lps.out;
}

// An oblique volume (rotated about z and mirrored in k, det -1, as radiological MRI often is):
// info shows the direction without a warning, `mesh` builds the grid mesh in its world frame
// (inside, positively oriented), `refine --fit-mesh-to-volume` fits a mesh into the rotated box,
// and `slice` cuts it.
TEST_F(CliMeshVerify, ObliqueVolumeMeshesRefinesAndSlicesInItsFrame) {
  const Volume bump = BumpVolume({11, 9, 7}, {-5.0, 0.0, 10.0}, {1.0, 1.5, 2.0});
  GridGeometry g = bump.grid();
  g.direction = {0.8, -0.6, 0.0, 0.6, 0.8, 0.0, 0.0, 0.0, -1.0};
  absl::StatusOr<Volume> oblique = Volume::CreateWhole(g, bump.type(), bump.data());
  ASSERT_TRUE(oblique.ok()) << oblique.status();
  volume_ = dir_.File("oblique.nii");
  WriteVolume(volume_, *oblique);

  const ProcessResult info = RunTetrefine({"info", volume_});
  ASSERT_EQ(info.exit_code, 0) << info.err;
  EXPECT_EQ(info.err, "");
  for (const char* text :
       {"direction", "oblique", "0.8", "-0.6", "orientation        oblique, closest to RAI"}) {
    EXPECT_TRUE(absl::StrContains(info.out, text)) << text << " missing from\n" << info.out;
  }

  const io::MeshFile mesh = MakeMesh("grid.vtu", {"--block", "3"});
  EXPECT_EQ(mesh.mesh.tets.size(), 5u * 4 * 3 * 2);
  EXPECT_TRUE(CheckFaces(mesh.mesh.points, mesh.mesh.tets).ok());
  // Its corner (0, 0, 0) is the volume's origin and (10, 0, 0) lies along the first column.
  EXPECT_EQ(mesh.mesh.points[0], (Vec3{-5.0, 0.0, 10.0}));
  const ProcessResult verified = Verify(dir_.File("grid.vtu"), {"--epsilon", "0.05"});
  EXPECT_EQ(verified.exit_code, 0) << verified.err << verified.out;
  // Same total volume as the axis-aligned grid (1440 mm^3): a rotation keeps volumes (up to the
  // float32 sform's rounding).
  EXPECT_TRUE(absl::StrContains(verified.out, "total volume          1440.0")) << verified.out;

  const std::string source = TETREFINE_SOURCE_DIR;
  const ProcessResult refine = RunTetrefine(
      {"refine", "--volume", volume_, "--mesh", source + "/examples/unit_cube_1782tets.mesh",
       "--fit-mesh-to-volume", "--epsilon", "0.1", "--max-iterations", "2", "--output",
       dir_.File("cube.vtu"), "--quiet"});
  ASSERT_EQ(refine.exit_code, 0) << refine.err;
  EXPECT_EQ(Verify(dir_.File("cube.vtu")).exit_code, 0);

  // A mesh inside the rotated grid's world box but not inside the grid: the error says which
  // grid index the vertex has and why the box did not tell.
  io::MeshFile corner;
  // World box [-12.2, 3] x [0, 15.6] x [-2, 10]; (2, 14, 5) is near its corner (3, 15.6), which
  // the rotated grid does not reach.
  corner.mesh.points = {{2.0, 14.0, 5.0}, {1.0, 14.0, 5.0}, {2.0, 13.0, 5.0}, {2.0, 14.0, 6.0}};
  corner.mesh.tets = {{0, 1, 2, 3}};
  ASSERT_TRUE(io::WriteMesh(dir_.File("corner.vtu"), corner).ok());
  const ProcessResult outside =
      RunTetrefine({"refine", "--volume", volume_, "--mesh", dir_.File("corner.vtu"), "--epsilon",
                    "0.1", "--output", dir_.File("corner_out.vtu")});
  EXPECT_EQ(outside.exit_code, 2) << outside.err;
  for (const char* text : {"corner.vtu: vertex 0 at (2, 14, 5) lies outside the volume",
                           "at grid index (14, 4.667, 2.5), outside [0, 10] x [0, 8] x [0, 6]",
                           "is oblique", "--fit-mesh-to-volume"}) {
    EXPECT_TRUE(absl::StrContains(outside.err, text)) << text << " missing from\n" << outside.err;
  }

  const ProcessResult slice = RunTetrefine({"slice", "--volume", volume_, "--mesh",
                                            dir_.File("grid.vtu"), "--output", dir_.File("s.png")});
  EXPECT_EQ(slice.exit_code, 0) << slice.err;
  EXPECT_TRUE(FileExists(dir_.File("s.png")));
}

// A grid whose axes are only flipped and swapped, as the shipped T1 volume's (i to the left, j
// up, k to the front): info names it by its axis codes, not as oblique, and a vertex outside it
// is told against its world box, which the grid fills (the message had called it oblique).
TEST_F(CliMeshVerify, FlippedAndSwappedAxesAreNotOblique) {
  const Volume bump = BumpVolume({11, 9, 7}, {-5.0, 0.0, 10.0}, {1.0, 1.5, 2.0});
  GridGeometry g = bump.grid();
  g.direction = {-1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 1.0, 0.0};
  absl::StatusOr<Volume> swapped = Volume::CreateWhole(g, bump.type(), bump.data());
  ASSERT_TRUE(swapped.ok()) << swapped.status();
  volume_ = dir_.File("lsa.nii");
  WriteVolume(volume_, *swapped);

  const ProcessResult info = RunTetrefine({"info", volume_});
  ASSERT_EQ(info.exit_code, 0) << info.err;
  for (const char* text :
       {"axes flipped or swapped, not oblique",
        "orientation        LSA (the file's i, j, k run to left, superior, anterior)"}) {
    EXPECT_TRUE(absl::StrContains(info.out, text)) << text << " missing from\n" << info.out;
  }

  // World box [-15, -5] x [0, 12] x [10, 22]: (0, 5, 15) lies beyond its x maximum.
  io::MeshFile outside;
  outside.mesh.points = {{0.0, 5.0, 15.0}, {-6.0, 5.0, 15.0}, {-6.0, 6.0, 15.0}, {-6.0, 5.0, 16.0}};
  outside.mesh.tets = {{0, 1, 2, 3}};
  ASSERT_TRUE(io::WriteMesh(dir_.File("outside.vtu"), outside).ok());
  const ProcessResult refine =
      RunTetrefine({"refine", "--volume", volume_, "--mesh", dir_.File("outside.vtu"), "--epsilon",
                    "0.1", "--output", dir_.File("outside_out.vtu")});
  EXPECT_EQ(refine.exit_code, 2) << refine.err;
  EXPECT_TRUE(absl::StrContains(refine.err, "outside.vtu: vertex 0 at (0, 5, 15) lies outside"))
      << refine.err;
  EXPECT_TRUE(absl::StrContains(refine.err, "world box [-15, -5] x [0, 12] x [10, 22]"))
      << refine.err;
  EXPECT_FALSE(absl::StrContains(refine.err, "oblique")) << refine.err;
}

TEST_F(CliMeshVerify, InfoOnAMesh) {
  MakeMesh("grid.vtu", {"--block", "3"});
  const ProcessResult run = RunTetrefine({"info", dir_.File("grid.vtu")});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  for (const char* text :
       {"tetrahedral mesh", "tets                  120", "[-5, 5] x [0, 12] x [10, 22]", "1440",
        "value (per vertex)", "inverted tets         0", "frame                 untagged"}) {
    EXPECT_TRUE(absl::StrContains(run.out, text)) << text << " missing from\n" << run.out;
  }
  EXPECT_FALSE(absl::StrContains(run.out, "regions")) << run.out;

  // Labels, the frame tag and the arrays refine does not carry are shown: "arrays none" on a
  // labelled file left a user unable to tell whether its labels had been recognised.
  io::MeshFile labelled;
  labelled.mesh = testing::FiveTetMesh({0, 0, 0}, {1, 1, 1}, {2, 1, 1});  // 10 tets
  labelled.mesh.labels = {11, 11, 11, 12, 12, 11, 11, 11, 11, 13};
  labelled.label_name = "gmsh:physical";
  labelled.frame = io::MeshFrame::kLps;
  ASSERT_TRUE(io::WriteMesh(dir_.File("labelled.vtu"), labelled).ok());
  const ProcessResult info = RunTetrefine({"info", dir_.File("labelled.vtu")});
  ASSERT_EQ(info.exit_code, 0) << info.err;
  for (const char* text : {"gmsh:physical (region label per tet)",
                           "regions               3: 11 (7 tets), 12 (2 tets), 13 (1 tet)",
                           "frame                 LPS (SPACE=LPS tag), read as RAS"}) {
    EXPECT_TRUE(absl::StrContains(info.out, text)) << text << " missing from\n" << info.out;
  }
  EXPECT_TRUE(absl::StrContains(info.out, "conformity            conformal")) << info.out;

  // A mesh listed twice (what a .pvtu whose pieces each hold the whole mesh reads as) is said to
  // be one: info gave three times the tets and volume with no word (a file-format sweep).
  io::MeshFile twice = labelled;
  const size_t n = twice.mesh.tets.size();
  for (size_t t = 0; t < n; ++t) {
    twice.mesh.tets.push_back(twice.mesh.tets[t]);
    twice.mesh.labels.push_back(twice.mesh.labels[t]);
  }
  ASSERT_TRUE(io::WriteMesh(dir_.File("twice.vtu"), twice).ok());
  const ProcessResult doubled = RunTetrefine({"info", dir_.File("twice.vtu")});
  ASSERT_EQ(doubled.exit_code, 0) << doubled.err;
  EXPECT_TRUE(absl::StrContains(doubled.out, "an element listed twice")) << doubled.out;
}

// verify bounds --norm-coeff as refine's service does: a value so small that the errors overflow
// printed "max inf" and "valid", exit 0 (a sweep, 2026-11-27).
TEST_F(CliMeshVerify, NormCoeffTooSmallForTheVolumeIsRefusedAsRefineRefusesIt) {
  MakeMesh("grid.vtu", {"--block", "3"});
  for (const char* norm : {"1e-300", "1e-310"}) {
    const ProcessResult verify = Verify(dir_.File("grid.vtu"), {"--norm-coeff", norm});
    EXPECT_EQ(verify.exit_code, 2) << norm << verify.out;
    // The flag the user typed and its value, not the wire's field (an outside review found
    // refine naming the mesh file and options.norm_coeff).
    EXPECT_TRUE(absl::StrContains(verify.err, absl::StrCat("tetrefine: --norm-coeff ", norm, ": ")))
        << verify.err;
    EXPECT_FALSE(absl::StrContains(verify.err, "options.norm_coeff")) << verify.err;
    const ProcessResult refine =
        RunTetrefine({"refine", "--volume", volume_, "--mesh", dir_.File("grid.vtu"), "--epsilon",
                      "0.1", "--norm-coeff", norm, "--output", dir_.File("out.vtu")});
    EXPECT_EQ(refine.exit_code, 2) << norm << refine.err;
    EXPECT_TRUE(absl::StrContains(refine.err, absl::StrCat("tetrefine: --norm-coeff ", norm, ": ")))
        << refine.err;
    EXPECT_TRUE(absl::StrContains(refine.err, volume_)) << refine.err;
    EXPECT_FALSE(absl::StrContains(refine.err, "options.norm_coeff")) << refine.err;
  }
  EXPECT_EQ(Verify(dir_.File("grid.vtu"), {"--norm-coeff", "1e-3"}).exit_code, 0);
  // A normalisation the values' rounding would swamp is named as the flag's too.
  const ProcessResult rounding =
      RunTetrefine({"refine", "--volume", volume_, "--mesh", dir_.File("grid.vtu"), "--epsilon",
                    "0.1", "--norm-coeff", "1e-270", "--output", dir_.File("out.vtu")});
  EXPECT_EQ(rounding.exit_code, 2) << rounding.err;
  EXPECT_TRUE(absl::StrContains(rounding.err, "tetrefine: --norm-coeff 1e-270: values reach "))
      << rounding.err;
  EXPECT_TRUE(absl::StrContains(rounding.err, "; give a larger --norm-coeff, or none for the "))
      << rounding.err;
  // verify applies the same bound: it printed a 200-digit discrepancy and "valid".
  const ProcessResult verify = Verify(dir_.File("grid.vtu"), {"--norm-coeff", "1e-270"});
  EXPECT_EQ(verify.exit_code, 2) << verify.out;
  EXPECT_TRUE(absl::StrContains(verify.err, "tetrefine: --norm-coeff 1e-270: values reach "))
      << verify.err;
}

}  // namespace
}  // namespace tetrefine::clitest
