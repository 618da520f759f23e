// tetrefine slice end to end: the PNG it writes decodes to the size it reports and shows what the
// inputs imply; bad flags and files give one line naming them, exit 2 and no file.

#include <filesystem>
#include <ostream>
#include <set>
#include <string>
#include <vector>

#include "absl/strings/match.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "client/io/read_volume.h"
#include "client/render/colormap.h"
#include "client/render/display_range.h"
#include "client/render/slice_figure.h"
#include "client/render/slice_plane.h"
#include "gtest/gtest.h"
#include "tests/cli/cli_test_util.h"
#include "tests/io/io_test_util.h"
#include "tests/render/png_image.h"
#include "tests/support/geometry.h"

namespace tetrefine::clitest {
namespace {

using io::iotest::ReadBytes;
using io::iotest::ScratchDir;
using render::testing::DecodePng;
using render::testing::Image;

// The figure's layout for the plane tetrefine slice draws of `volume_path`.
render::FigureLayout ExpectedLayout(const std::string& volume_path, int axis, double position,
                                    int rows, int panel_size = 320) {
  absl::StatusOr<io::VolumeFile> volume = io::ReadVolume(volume_path);
  EXPECT_TRUE(volume.ok()) << volume.status();
  absl::StatusOr<render::SlicePlane> plane =
      render::MakeSlicePlane(volume->volume, axis, position, panel_size);
  EXPECT_TRUE(plane.ok()) << plane.status();
  return render::LayoutFigure(rows, plane->width, plane->height);
}

TEST(CliSlice, BeforeAndAfterMakeATwoRowPngOfTheReportedSize) {
  ScratchDir dir;
  WriteVolume(dir.File("v.nii"), BumpVolume({17, 13, 9}, {-8, -6, 0}, {1, 1, 1}));
  WriteMeshFile(dir.File("before.vtu"), testing::FiveTetMesh({-7, -5, 1}, {7, 5, 7}, {2, 2, 2}));
  WriteMeshFile(dir.File("after.vtu"), testing::FiveTetMesh({-7, -5, 1}, {7, 5, 7}, {7, 5, 3}));
  const ProcessResult run = RunTetrefine(
      {"slice", "--volume", dir.File("v.nii"), "--mesh", dir.File("before.vtu"), "--mesh-after",
       dir.File("after.vtu"), "--axis", "y", "--position", "0.5", "--output", dir.File("f.png")});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_EQ(run.err, "");
  const render::FigureLayout layout = ExpectedLayout(dir.File("v.nii"), 1, 0.5, 2);
  EXPECT_TRUE(
      absl::StrContains(run.out, absl::StrCat("Wrote ", dir.File("f.png"), ": ", layout.width,
                                              " x ", layout.height, " pixels, plane y = 0.5 mm")))
      << run.out;
  EXPECT_TRUE(absl::StrContains(run.out, "before: " + dir.File("before.vtu") + ": 40 tets"))
      << run.out;
  EXPECT_TRUE(absl::StrContains(run.out, "after: " + dir.File("after.vtu") + ": 525 tets"));
  absl::StatusOr<Image> image = DecodePng(ReadBytes(dir.File("f.png")));
  ASSERT_TRUE(image.ok()) << image.status();
  EXPECT_EQ(image->width, layout.width);
  EXPECT_EQ(image->height, layout.height);
  // The finer mesh follows the bump better: less discrepancy-coloured area in the second row.
  const auto brightness = [&](const render::PixelRect& panel) {
    double sum = 0.0;
    for (int y = panel.y; y < panel.y + panel.height; ++y) {
      for (int x = panel.x; x < panel.x + panel.width; ++x) {
        const render::Rgb c = image->At(x, y);
        if (c == render::kNoMeshColour) continue;
        sum += c.r + c.g + c.b;
      }
    }
    return sum;
  };
  EXPECT_GT(brightness(layout.rows[0].discrepancy), brightness(layout.rows[1].discrepancy));
}

// The mesh's field is the volume sampled at its vertices, as refine and verify take it: a
// `value` array in the file that says otherwise (a mesh refined in another or rescaled scan) is
// named and not drawn. It was drawn, and the picture showed a discrepancy verify did not see
// (an outside review, 2026-11-28).
TEST(CliSlice, ALinearVolumeGivesAZeroDiscrepancyPanelWhateverTheFilesValues) {
  ScratchDir dir;
  const GridGeometry grid{{9, 9, 9}, {0, 0, 0}, {1, 1, 1}};
  WriteVolume(dir.File("v.nii"), testing::AnalyticVolume(grid, [](const Vec3& p) {
                return 2.0 * p[0] + p[1] - 3.0 * p[2];
              }));
  Mesh mesh = testing::FiveTetMesh({0, 0, 0}, {8, 8, 8}, {2, 2, 2});
  WriteMeshFile(dir.File("m.vtu"), mesh);
  mesh.values.assign(mesh.points.size(), 0.0);  // a flat field instead of the volume's
  WriteMeshFile(dir.File("flat.vtu"), mesh);
  const ProcessResult run = RunTetrefine({"slice", "--volume", dir.File("v.nii"), "--mesh",
                                          dir.File("m.vtu"), "--mesh-after", dir.File("flat.vtu"),
                                          "--no-edges", "--output", dir.File("f.png")});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_TRUE(absl::StrContains(run.err, absl::StrCat(dir.File("flat.vtu"),
                                                      ": the file's value array differs from the "
                                                      "volume at 24 of 27 vertices")))
      << run.err;
  EXPECT_TRUE(absl::StrContains(run.err, "the picture uses the volume's samples")) << run.err;
  EXPECT_FALSE(absl::StrContains(run.err, dir.File("m.vtu"))) << run.err;
  absl::StatusOr<Image> image = DecodePng(ReadBytes(dir.File("f.png")));
  ASSERT_TRUE(image.ok()) << image.status();
  // Default: axis z through the middle of the volume (z = 4).
  const render::FigureLayout layout = ExpectedLayout(dir.File("v.nii"), 2, 4.0, 2);
  ASSERT_EQ(image->width, layout.width);
  for (const render::FigureLayout::Row& row : layout.rows) {
    const render::PixelRect& panel = row.discrepancy;
    for (int y = panel.y; y < panel.y + panel.height; ++y) {
      for (int x = panel.x; x < panel.x + panel.width; ++x) {
        ASSERT_EQ(image->At(x, y), render::DiscrepancyColour(0.0)) << x << ", " << y;
      }
    }
  }
  EXPECT_TRUE(absl::StrContains(run.out, "discrepancy on the plane max 0.000000")) << run.out;
}

// A value array written with fewer digits (VTK's legacy ASCII writer keeps 6) is the volume's
// samples all the same: no warning (an outside review saw one for 1.6e-6 of the range).
TEST(CliSlice, ValuesRoundedToSixDigitsAreNotADifference) {
  ScratchDir dir;
  const GridGeometry grid{{9, 9, 9}, {0, 0, 0}, {1, 1, 1}};
  WriteVolume(dir.File("v.nii"), testing::AnalyticVolume(grid, [](const Vec3& p) {
                return 3.0e7 + 1.2345678 * p[0] + 0.5 * p[1];
              }));
  Mesh mesh = testing::FiveTetMesh({0, 0, 0}, {8, 8, 8}, {2, 2, 2});
  mesh.values.clear();
  for (const Vec3& p : mesh.points) {
    mesh.values.push_back(
        std::stod(absl::StrFormat("%.6g", 3.0e7 + 1.2345678 * p[0] + 0.5 * p[1])));
  }
  WriteMeshFile(dir.File("six.vtu"), mesh);
  const ProcessResult run = RunTetrefine({"slice", "--volume", dir.File("v.nii"), "--mesh",
                                          dir.File("six.vtu"), "--output", dir.File("f.png")});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_EQ(run.err, "");
}

// A mesh outside the volume is named, with where it is and where the volume is; a plane that
// meets the mesh only outside the volume says there is nothing to compare, instead of printing
// "max 0, mean 0" alone, which read as a perfect mesh.
TEST(CliSlice, AMeshOutsideTheVolumeIsNamedNotShownAsPerfect) {
  ScratchDir dir;
  WriteVolume(dir.File("v.nii"), BumpVolume({17, 13, 9}, {-8, -6, 0}, {1, 1, 1}));
  WriteMeshFile(dir.File("far.vtu"), testing::FiveTetMesh({493, -5, 1}, {507, 5, 7}, {2, 2, 2}));
  WriteMeshFile(dir.File("part.vtu"), testing::FiveTetMesh({0, -5, 1}, {14, 5, 7}, {2, 2, 2}));
  const ProcessResult far = RunTetrefine({"slice", "--volume", dir.File("v.nii"), "--mesh",
                                          dir.File("far.vtu"), "--output", dir.File("far.png")});
  ASSERT_EQ(far.exit_code, 0) << far.err;
  EXPECT_TRUE(
      absl::StrContains(far.err, "27 of 27 vertices lie outside the volume (first: vertex "))
      << far.err;
  EXPECT_TRUE(absl::StrContains(far.err, "the volume spans [-8, 8] x [-6, 6] x [0, 8] mm"))
      << far.err;
  EXPECT_TRUE(absl::StrContains(far.err, "cuts the mesh only outside the volume")) << far.err;
  // Nor does the summary line give a max and mean of nothing (it said "max 0.000000, mean
  // 0.000000 over 0 pixels").
  EXPECT_TRUE(absl::StrContains(far.out, "no discrepancy on the plane (no pixel has both values)"))
      << far.out;
  EXPECT_FALSE(absl::StrContains(far.out, "over 0 pixels")) << far.out;
  const ProcessResult part = RunTetrefine({"slice", "--volume", dir.File("v.nii"), "--mesh",
                                           dir.File("part.vtu"), "--output", dir.File("part.png")});
  ASSERT_EQ(part.exit_code, 0) << part.err;
  EXPECT_TRUE(absl::StrContains(part.err, "vertices lie outside the volume")) << part.err;
  EXPECT_FALSE(absl::StrContains(part.err, "cuts the mesh only outside")) << part.err;
  EXPECT_TRUE(absl::StrContains(part.out, "discrepancy on the plane max ")) << part.out;
  // A plane inside the volume that misses the mesh (z 1 to 7) is named, and so is what it shows.
  const ProcessResult miss =
      RunTetrefine({"slice", "--volume", dir.File("v.nii"), "--mesh", dir.File("part.vtu"),
                    "--position", "0.5", "--output", dir.File("miss.png")});
  ASSERT_EQ(miss.exit_code, 0) << miss.err;
  EXPECT_TRUE(absl::StrContains(miss.err, "the plane z = 0.5 mm cuts no tet")) << miss.err;
  EXPECT_TRUE(absl::StrContains(miss.out, "0 cut by the plane; no discrepancy on the plane"))
      << miss.out;
}

struct BadCase {
  std::string name;
  std::vector<std::string> args;  // "$D/" is replaced by the scratch directory
  std::string expected;           // must appear in the error line ("$D/" replaced too)
};

void PrintTo(const BadCase& c, std::ostream* os) { *os << c.name; }

std::string Expand(std::string text, const std::string& dir) {
  for (size_t at = text.find("$D/"); at != std::string::npos; at = text.find("$D/")) {
    text.replace(at, 3, dir + "/");
  }
  return text;
}

std::set<std::string> Listing(const std::string& dir) {
  std::set<std::string> names;
  for (const auto& entry : std::filesystem::directory_iterator(dir)) {
    names.insert(entry.path().filename().string());
  }
  return names;
}

class CliSliceBadInput : public ::testing::TestWithParam<BadCase> {
 protected:
  static void SetUpTestSuite() {
    dir_ = new ScratchDir();
    WriteVolume(dir_->File("v.nii"), BumpVolume({9, 9, 9}, {0, 0, 0}, {1, 1, 1}));
    WriteMeshFile(dir_->File("m.vtu"), testing::FiveTetMesh({1, 1, 1}, {7, 7, 7}, {2, 2, 2}));
    io::iotest::WriteBytes(dir_->File("garbage.vtu"), "not XML\n");
  }
  static void TearDownTestSuite() {
    delete dir_;
    dir_ = nullptr;
  }
  static ScratchDir* dir_;
};

ScratchDir* CliSliceBadInput::dir_ = nullptr;

TEST_P(CliSliceBadInput, OneLineNamingTheProblemExitTwoNothingWritten) {
  const BadCase& c = GetParam();
  std::vector<std::string> args = {"slice"};
  for (const std::string& a : c.args) args.push_back(Expand(a, dir_->path()));
  const std::set<std::string> before = Listing(dir_->path());
  const ProcessResult run = RunTetrefine(args, "", /*timeout_seconds=*/60);
  EXPECT_EQ(run.exit_code, 2) << run.err;
  const std::vector<std::string> lines = SplitLines(run.err);
  ASSERT_EQ(lines.size(), 1u) << "stderr:\n" << run.err;
  const std::string expected = Expand(c.expected, dir_->path());
  EXPECT_TRUE(absl::StartsWith(lines[0], "tetrefine: ")) << lines[0];
  EXPECT_TRUE(absl::StrContains(lines[0], expected))
      << "'" << lines[0] << "' should contain '" << expected << "'";
  EXPECT_EQ(run.out, "");
  EXPECT_EQ(Listing(dir_->path()), before) << "a file was created or removed";
}

std::vector<std::string> Slice(std::vector<std::string> extra) {
  std::vector<std::string> args = {"--volume", "$D/v.nii", "--mesh",
                                   "$D/m.vtu", "--output", "$D/f.png"};
  args.insert(args.end(), extra.begin(), extra.end());
  return args;
}

INSTANTIATE_TEST_SUITE_P(
    Flags, CliSliceBadInput,
    ::testing::Values(
        BadCase{"axis", Slice({"--axis", "w"}), "--axis: expected x, y or z, got 'w'"},
        BadCase{"position_outside", Slice({"--position", "9"}),
                "--position: 9 mm is outside the volume's z range [0, 8] mm ($D/v.nii)"},
        BadCase{"position_text", Slice({"--position", "middle"}), "--position"},
        BadCase{"panel_size", Slice({"--panel-size", "3"}), "--panel-size"},
        BadCase{"discrepancy_max", Slice({"--discrepancy-max", "-1"}),
                "--discrepancy-max: must be > 0, got '-1'"},
        BadCase{"not_png",
                {"--volume", "$D/v.nii", "--mesh", "$D/m.vtu", "--output", "$D/f.jpg"},
                "$D/f.jpg: --output takes a .png file"},
        BadCase{"no_output_dir",
                {"--volume", "$D/v.nii", "--mesh", "$D/m.vtu", "--output", "$D/no/f.png"},
                "$D/no/f.png: directory $D/no does not exist (--output)"},
        BadCase{"missing_output", {"--volume", "$D/v.nii", "--mesh", "$D/m.vtu"}, "--output"},
        BadCase{"missing_mesh_file",
                {"--volume", "$D/v.nii", "--mesh", "$D/none.vtu", "--output", "$D/f.png"},
                "$D/none.vtu"},
        BadCase{"garbage_mesh_after", Slice({"--mesh-after", "$D/garbage.vtu"}), "$D/garbage.vtu"},
        BadCase{"mesh_as_volume",
                {"--volume", "$D/m.vtu", "--mesh", "$D/m.vtu", "--output", "$D/f.png"},
                "$D/m.vtu: is a mesh, but --volume takes a volume"},
        BadCase{"unknown_flag", Slice({"--colour", "red"}), "unknown flag --colour"}),
    [](const ::testing::TestParamInfo<BadCase>& info) { return info.param.name; });

}  // namespace
}  // namespace tetrefine::clitest
