// Bad input to every subcommand (issue 4): one line on stderr naming the file or flag, exit code
// 2, nothing written, never a crash.

#include <filesystem>
#include <ostream>
#include <set>
#include <string>
#include <vector>

#include "absl/strings/match.h"
#include "gtest/gtest.h"
#include "tests/cli/cli_test_util.h"
#include "tests/io/io_test_util.h"
#include "tests/support/geometry.h"

namespace tetrefine::clitest {
namespace {

using io::iotest::ReadBytes;
using io::iotest::ScratchDir;
using io::iotest::WriteBytes;

struct BadCase {
  std::string name;
  std::vector<std::string> args;  // "$D/" is replaced by the scratch directory
  std::string expected;           // must appear in the error line ("$D/" replaced too)
};

// gtest prints parameters of failing tests; the name is what identifies a case.
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

class CliBadInput : public ::testing::TestWithParam<BadCase> {
 protected:
  static void SetUpTestSuite() {
    dir_ = new ScratchDir();
    const std::string volume = dir_->File("v.nii");
    WriteVolume(volume, BumpVolume({9, 9, 9}, {0.0, 0.0, 0.0}, {1.0, 1.0, 1.0}));
    const Mesh grid = testing::FiveTetMesh({1, 1, 1}, {7, 7, 7}, {2, 2, 2});
    WriteMeshFile(dir_->File("m.vtu"), grid);
    std::filesystem::create_hard_link(dir_->File("m.vtu"), dir_->File("m_linked.vtu"));
    WriteMeshFile(dir_->File("m.msh"), grid);
    const std::string nifti = ReadBytes(volume);
    const std::string vtu = ReadBytes(dir_->File("m.vtu"));
    const std::string msh = ReadBytes(dir_->File("m.msh"));
    WriteBytes(dir_->File("truncated.nii"), nifti.substr(0, 200));
    WriteBytes(dir_->File("short_data.nii"), nifti.substr(0, nifti.size() - 100));
    WriteBytes(dir_->File("garbage.nii"), std::string(400, '\x7f'));
    WriteBytes(dir_->File("empty.nii"), "");
    WriteBytes(dir_->File("garbage.vtu"), "this is not XML at all\n");
    WriteBytes(dir_->File("truncated.vtu"), vtu.substr(0, vtu.size() / 2));
    WriteBytes(dir_->File("truncated.msh"), msh.substr(0, msh.size() / 2));
    WriteBytes(dir_->File("empty.vtu"), "");
    WriteBytes(dir_->File("m.obj"), vtu);
    WriteBytes(dir_->File("v.xyz"), nifti);
    Mesh outside = grid;
    for (Vec3& p : outside.points) p[0] += 100.0;
    WriteMeshFile(dir_->File("outside.vtu"), outside);
    Mesh unused_outside = grid;
    unused_outside.points.push_back({100.0, 100.0, 100.0});
    WriteMeshFile(dir_->File("unused_outside.vtu"), unused_outside);
    Mesh inverted = grid;
    std::swap(inverted.tets[3][2], inverted.tets[3][3]);
    WriteMeshFile(dir_->File("inverted.vtu"), inverted);
    Mesh no_tets;
    no_tets.points = grid.points;
    WriteMeshFile(dir_->File("no_tets.vtu"), no_tets);
    WriteBytes(dir_->File("empty.inp"), "");
    std::filesystem::create_directory(dir_->File("adir.vtu"));
  }
  static void TearDownTestSuite() {
    delete dir_;
    dir_ = nullptr;
  }

  static ScratchDir* dir_;
};

ScratchDir* CliBadInput::dir_ = nullptr;

TEST_P(CliBadInput, OneLineNamingTheProblemExitTwoNothingWritten) {
  const BadCase& c = GetParam();
  std::vector<std::string> args;
  for (const std::string& a : c.args) args.push_back(Expand(a, dir_->path()));
  const std::set<std::string> before = Listing(dir_->path());
  const ProcessResult run = RunTetrefine(args, "", /*timeout_seconds=*/60);
  EXPECT_FALSE(run.timed_out);
  EXPECT_EQ(run.exit_code, 2) << run.err;
  // refine reports its phases (reading the volume, the mesh) before the error: those lines come
  // first, each ended ("... 0.05 s", or "... failed" for the phase the error is about).
  std::vector<std::string> lines = SplitLines(run.err);
  ASSERT_GE(lines.size(), 1u) << "stderr:\n" << run.err;
  const std::string error = lines.back();
  lines.pop_back();
  for (const std::string& line : lines) {
    EXPECT_TRUE(absl::StartsWith(line, "tetrefine: reading ") &&
                (absl::EndsWith(line, " s") || absl::EndsWith(line, " ... failed")))
        << "not a progress line: " << line << "\nstderr:\n"
        << run.err;
  }
  EXPECT_TRUE(absl::StartsWith(error, "tetrefine: ")) << error;
  const std::string expected = Expand(c.expected, dir_->path());
  EXPECT_TRUE(absl::StrContains(error, expected))
      << "'" << error << "' should contain '" << expected << "'";
  EXPECT_EQ(run.out, "");
  EXPECT_EQ(Listing(dir_->path()), before) << "a file was created or removed";
  if (!args.empty() && args[0] == "refine") {
    // Without progress the error is the only line.
    args.insert(args.begin() + 1, "--quiet");
    const ProcessResult quiet = RunTetrefine(args, "", /*timeout_seconds=*/60);
    EXPECT_EQ(quiet.exit_code, 2) << quiet.err;
    EXPECT_EQ(quiet.err, error + "\n");
  }
}

const std::vector<std::string> kRefine = {"refine",   "--volume", "$D/v.nii",  "--mesh",
                                          "$D/m.vtu", "--output", "$D/out.vtu"};

std::vector<std::string> Refine(std::vector<std::string> extra,
                                std::vector<std::string> base = kRefine) {
  base.insert(base.end(), extra.begin(), extra.end());
  return base;
}

// kRefine with flag `name`'s value replaced (or the flag dropped when value is empty).
std::vector<std::string> RefineWith(const std::string& name, const std::string& value,
                                    std::vector<std::string> extra = {"--epsilon", "0.1"}) {
  std::vector<std::string> args;
  for (size_t i = 0; i < kRefine.size(); ++i) {
    if (kRefine[i] == name) {
      if (!value.empty()) args.insert(args.end(), {name, value});
      ++i;
      continue;
    }
    args.push_back(kRefine[i]);
  }
  args.insert(args.end(), extra.begin(), extra.end());
  return args;
}

INSTANTIATE_TEST_SUITE_P(
    CliRefineArgs, CliBadInput,
    ::testing::Values(
        BadCase{"MissingEpsilon", Refine({}), "--epsilon"},
        BadCase{"MissingVolume", RefineWith("--volume", ""), "--volume"},
        BadCase{"MissingMesh", RefineWith("--mesh", ""), "--mesh"},
        BadCase{"EpsilonZero", Refine({"--epsilon", "0"}), "--epsilon"},
        BadCase{"EpsilonNegative", Refine({"--epsilon", "-0.1"}), "--epsilon"},
        BadCase{"EpsilonNaN", Refine({"--epsilon", "nan"}), "--epsilon"},
        BadCase{"EpsilonInf", Refine({"--epsilon", "inf"}), "--epsilon"},
        BadCase{"EpsilonText", Refine({"--epsilon", "ten percent"}), "--epsilon"},
        BadCase{"EpsilonEmpty", Refine({"--epsilon="}), "--epsilon"},
        BadCase{"EpsilonNoValue", Refine({"--epsilon"}), "--epsilon"},
        BadCase{"MaxIterationsNegative", Refine({"--epsilon", "0.1", "--max-iterations", "-1"}),
                "--max-iterations"},
        BadCase{"MaxTetsZero", Refine({"--epsilon", "0.1", "--max-tets", "0"}), "--max-tets"},
        BadCase{"MaxIterationsHuge",
                Refine({"--epsilon", "0.1", "--max-iterations", "99999999999999999999"}),
                "--max-iterations: expected a whole number in [0, 2147483647]"},
        BadCase{"MaxTetsBelowTheInput", Refine({"--epsilon", "0.1", "--max-tets", "3"}),
                "--max-tets 3 is below the 40 tets of $D/m.vtu"},
        BadCase{"CertifyOnTheCorners",
                Refine({"--epsilon", "0.1", "--certify", "--lattice-n", "1"}),
                "--lattice-n: certify needs a lattice with points inside the tets"},
        BadCase{"ThreadsText", Refine({"--epsilon", "0.1", "--threads", "many"}), "--threads"},
        BadCase{"NormCoeffZero", Refine({"--epsilon", "0.1", "--norm-coeff", "0"}), "--norm-coeff"},
        BadCase{"QualityReferenceAboveOne",
                Refine({"--epsilon", "0.1", "--quality-reference", "1.5"}), "--quality-reference"},
        BadCase{"UnknownFlag", Refine({"--epsilon", "0.1", "--shards", "4"}), "--shards"},
        BadCase{"VolumeMissing", RefineWith("--volume", "$D/nothere.nii"), "$D/nothere.nii"},
        BadCase{"VolumeTruncatedHeader", RefineWith("--volume", "$D/truncated.nii"),
                "$D/truncated.nii"},
        BadCase{"VolumeTruncatedData", RefineWith("--volume", "$D/short_data.nii"),
                "$D/short_data.nii"},
        BadCase{"VolumeGarbage", RefineWith("--volume", "$D/garbage.nii"), "$D/garbage.nii"},
        BadCase{"VolumeEmpty", RefineWith("--volume", "$D/empty.nii"), "$D/empty.nii"},
        BadCase{"VolumeUnknownExtension", RefineWith("--volume", "$D/v.xyz"), "$D/v.xyz"},
        BadCase{"VolumeIsAMesh", RefineWith("--volume", "$D/m.vtu"), "$D/m.vtu"},
        BadCase{"MeshMissing", RefineWith("--mesh", "$D/nothere.vtu"), "$D/nothere.vtu"},
        BadCase{"MeshGarbage", RefineWith("--mesh", "$D/garbage.vtu"), "$D/garbage.vtu"},
        BadCase{"MeshTruncatedVtu", RefineWith("--mesh", "$D/truncated.vtu"), "$D/truncated.vtu"},
        BadCase{"MeshTruncatedMsh", RefineWith("--mesh", "$D/truncated.msh"), "$D/truncated.msh"},
        BadCase{"MeshEmptyFile", RefineWith("--mesh", "$D/empty.vtu"), "$D/empty.vtu"},
        BadCase{"MeshIsADirectory", RefineWith("--mesh", "$D/adir.vtu"), "$D/adir.vtu"},
        BadCase{"MeshUnknownExtension", RefineWith("--mesh", "$D/m.obj"), "$D/m.obj"},
        BadCase{"MeshIsAVolume", RefineWith("--mesh", "$D/v.nii"), "$D/v.nii"},
        BadCase{"MeshOutsideVolume", RefineWith("--mesh", "$D/outside.vtu"), "$D/outside.vtu"},
        BadCase{"UnusedVertexOutsideVolume", RefineWith("--mesh", "$D/unused_outside.vtu"),
                "no tet uses it: remove the unused vertices"},
        // Named as every other message names a tet (it said "tet 3" alone).
        BadCase{"MeshInverted", RefineWith("--mesh", "$D/inverted.vtu"),
                "$D/inverted.vtu: mesh.tets[3] is inverted (negative volume); use "
                "--fix-orientation"},
        BadCase{"MeshWithoutTets", RefineWith("--mesh", "$D/no_tets.vtu"), "$D/no_tets.vtu"},
        // info reported such files as tetrahedral meshes of 0 tets (an outside review,
        // 2026-11-28); every command now refuses them alike.
        BadCase{"InfoOfMeshWithoutTets",
                {"info", "$D/no_tets.vtu"},
                "$D/no_tets.vtu: no tetrahedra (27 vertices): not a volume mesh"},
        BadCase{"InfoOfAnEmptyInp", {"info", "$D/empty.inp"}, "$D/empty.inp: no tetrahedra"},
        BadCase{"OutputUnknownExtension", RefineWith("--output", "$D/out.obj"), "$D/out.obj"},
        BadCase{"OutputDirectoryMissing", RefineWith("--output", "$D/no/such/out.vtu"),
                "$D/no/such/out.vtu"},
        BadCase{"OutputIsADirectory", RefineWith("--output", "$D/adir.vtu"), "$D/adir.vtu"},
        BadCase{"OutputUnderAFile", RefineWith("--output", "$D/m.msh/out.vtu"),
                "$D/m.msh/out.vtu: $D/m.msh is not a directory (--output)"},
        BadCase{"StatsDirectoryMissing",
                Refine({"--epsilon", "0.1", "--stats-json", "$D/no/stats.json"}),
                "$D/no/stats.json"},
        // The other files the run writes (an outside review: exit 0, an unreadable result).
        BadCase{"StatsJsonIsTheNodeFile",
                RefineWith("--output", "$D/out.ele",
                           {"--epsilon", "0.1", "--stats-json", "$D/out.node"}),
                "$D/out.node: --stats-json names the same file as the .node file of --output"},
        BadCase{
            "StatsJsonIsAnIterationFile",
            Refine({"--epsilon", "0.1", "--every-iteration", "--stats-json", "$D/out.iter02.vtu"}),
            "--stats-json names the same file as --every-iteration's file of iteration 2"},
        BadCase{"StatsJsonIsTheSeries",
                Refine({"--epsilon", "0.1", "--every-iteration", "--stats-json", "$D/out.pvd"}),
                "--stats-json names the same file as --every-iteration's series"},
        // No written file may be an input (a second review: --output replaced the input mesh,
        // or a legacy .vtk volume with a tet mesh, with exit 0).
        BadCase{"OutputIsTheMesh", RefineWith("--output", "$D/m.vtu"),
                "$D/m.vtu: --output names the same file as --mesh"},
        BadCase{"OutputIsTheMeshByAnotherName", RefineWith("--output", "$D/./m.vtu"),
                "--output names the same file as --mesh ($D/m.vtu)"},
        // A hard link is the same file under another name (an outside review refined into one).
        BadCase{"OutputIsTheMeshThroughAHardLink", RefineWith("--output", "$D/m_linked.vtu"),
                "$D/m_linked.vtu: --output names the same file as --mesh ($D/m.vtu)"},
        BadCase{"OutputIsTheVolume",
                Refine({"--epsilon", "0.1", "--output", "$D/image.vtk"},
                       {"refine", "--volume", "$D/image.vtk", "--mesh", "$D/m.vtu"}),
                "$D/image.vtk: --output names the same file as --volume"},
        BadCase{
            "StatsJsonIsTheInputsNodeFile",
            RefineWith("--mesh", "$D/in.ele", {"--epsilon", "0.1", "--stats-json", "$D/in.node"}),
            "$D/in.node: --stats-json names the same file as the .node file of --mesh"},
        BadCase{"AnIterationSeriesOfANameThatIsAllExtension",
                RefineWith("--output", "$D/.vtu", {"--epsilon", "0.1", "--every-iteration"}),
                "$D/.vtu: --output needs a name before its extension with --every-iteration"},
        BadCase{
            "AnIterationFileIsTheMesh",
            RefineWith("--mesh", "$D/out.iter01.vtu", {"--epsilon", "0.1", "--every-iteration"}),
            "$D/out.iter01.vtu: --every-iteration's file of iteration 1 names the same file as "
            "--mesh"},
        BadCase{"TlsWithoutServer", Refine({"--epsilon", "0.1", "--tls-ca", "$D/ca.pem"}),
                "--tls-ca"},
        BadCase{"TlsCertWithoutKey",
                Refine({"--epsilon", "0.1", "--server", "127.0.0.1:1", "--tls-cert", "$D/c.pem"}),
                "--tls-key"},
        BadCase{"ServerIsAUrl", Refine({"--epsilon", "0.1", "--server", "http://127.0.0.1:50051"}),
                "--server: 'http://127.0.0.1:50051' is a URL; write host:port without http://"},
        BadCase{"ServerPortOutOfRange",
                Refine({"--epsilon", "0.1", "--server", "127.0.0.1:1,127.0.0.1:65536"}),
                "--server: port 65536 of '127.0.0.1:65536' is out of range"},
        BadCase{"TlsCaUnreadable",
                Refine({"--epsilon", "0.1", "--server", "127.0.0.1:1", "--tls-ca", "$D/no.pem"}),
                "$D/no.pem"}),
    [](const ::testing::TestParamInfo<BadCase>& info) { return info.param.name; });

INSTANTIATE_TEST_SUITE_P(
    CliOtherArgs, CliBadInput,
    ::testing::Values(
        BadCase{"NoCommand", {}, "tetrefine"}, BadCase{"UnknownCommand", {"refien"}, "refien"},
        BadCase{"MeshMissingOutput", {"mesh", "--volume", "$D/v.nii"}, "--output"},
        BadCase{"MeshOutputIsTheVolume",
                {"mesh", "--volume", "$D/image.vtk", "--output", "$D/image.vtk"},
                "$D/image.vtk: --output names the same file as --volume"},
        BadCase{"MeshBlockZero",
                {"mesh", "--volume", "$D/v.nii", "--block", "0", "--output", "$D/g.vtu"},
                "--block"},
        BadCase{"MeshThresholdNaN",
                {"mesh", "--volume", "$D/v.nii", "--mask-threshold", "nan", "--output", "$D/g.vtu"},
                "--mask-threshold"},
        BadCase{"MeshVolumeTruncated",
                {"mesh", "--volume", "$D/truncated.nii", "--output", "$D/g.vtu"},
                "$D/truncated.nii"},
        BadCase{"MeshOutputUnknownExtension",
                {"mesh", "--volume", "$D/v.nii", "--output", "$D/g.stl"},
                "$D/g.stl"},
        BadCase{"VerifyMeshTruncated",
                {"verify", "--volume", "$D/v.nii", "--mesh", "$D/truncated.vtu"},
                "$D/truncated.vtu"},
        BadCase{"VerifyVolumeGarbage",
                {"verify", "--volume", "$D/garbage.nii", "--mesh", "$D/m.vtu"},
                "$D/garbage.nii"},
        BadCase{"VerifyEpsilonNegative",
                {"verify", "--volume", "$D/v.nii", "--mesh", "$D/m.vtu", "--epsilon", "-1"},
                "--epsilon"},
        BadCase{"VerifyMissingMesh", {"verify", "--volume", "$D/v.nii"}, "--mesh"},
        BadCase{"InfoMissingFile", {"info"}, "FILE"},
        BadCase{"InfoUnreadable", {"info", "$D/nothere.nii"}, "$D/nothere.nii"},
        BadCase{"InfoTruncatedVolume", {"info", "$D/truncated.nii"}, "$D/truncated.nii"},
        BadCase{"InfoTruncatedMesh", {"info", "$D/truncated.msh"}, "$D/truncated.msh"},
        BadCase{"InfoUnknownExtension", {"info", "$D/m.obj"}, "$D/m.obj"},
        BadCase{"InfoTwoFiles", {"info", "$D/v.nii", "$D/m.vtu"}, "$D/m.vtu"},
        BadCase{"HealthMissingServer", {"health"}, "--server"},
        // gRPC would take 70000 modulo 65536 and ask port 4464, somebody else's.
        BadCase{"HealthPortOutOfRange",
                {"health", "--server", "127.0.0.1:70000"},
                "--server: port 70000 of '127.0.0.1:70000' is out of range (1-65535)"},
        BadCase{"HealthTimeoutZero",
                {"health", "--server", "127.0.0.1:1", "--timeout", "0"},
                "--timeout"}),
    [](const ::testing::TestParamInfo<BadCase>& info) { return info.param.name; });

}  // namespace
}  // namespace tetrefine::clitest
