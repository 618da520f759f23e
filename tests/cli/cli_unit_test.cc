// Unit tests of the pieces of the tetrefine command line: argument parsing, JSON, the grid
// mesher, mesh fitting and the mesh report. Suites are named Cli* (`ctest -R '^Cli'`).

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "absl/strings/match.h"
#include "client/cli/arg_parser.h"
#include "client/cli/file_kind.h"
#include "client/cli/grid_mesher.h"
#include "client/cli/grpc_channel.h"
#include "client/cli/mesh_placement.h"
#include "client/cli/mesh_report.h"
#include "client/cli/refine_report.h"
#include "client/cli/stats_json.h"
#include "client/cli/text_table.h"
#include "client/io/json_writer.h"
#include "core/mesh_validation.h"
#include "gtest/gtest.h"
#include "tests/cli/cli_test_util.h"
#include "tests/support/geometry.h"

namespace tetrefine::cli {

using io::JsonWriter;
namespace {

CommandSpec TestSpec() {
  return CommandSpec{.name = "test",
                     .summary = "a test command",
                     .usage = "tetrefine test --in F",
                     .description = "",
                     .flags = {{"in", "F", "input", true},
                               {"max-count", "N", "a number"},
                               {"loud", "", "a switch"}},
                     .positional = ""};
}

TEST(CliArgParser, AcceptsBothValueFormsSwitchesAndUnderscores) {
  absl::StatusOr<ParsedArgs> parsed =
      ParseArgs(TestSpec(), {"--in", "a.nii", "--max_count=3", "--loud"});
  ASSERT_TRUE(parsed.ok()) << parsed.status();
  EXPECT_EQ(parsed->Get("in"), "a.nii");
  EXPECT_EQ(parsed->Get("max-count"), "3");
  EXPECT_TRUE(parsed->Has("loud"));
  EXPECT_FALSE(parsed->help());
}

TEST(CliArgParser, NegativeNumbersAreValues) {
  absl::StatusOr<ParsedArgs> parsed = ParseArgs(TestSpec(), {"--in", "x", "--max-count", "-5"});
  ASSERT_TRUE(parsed.ok()) << parsed.status();
  EXPECT_EQ(parsed->Get("max-count"), "-5");
}

TEST(CliArgParser, ErrorsNameTheFlag) {
  const CommandSpec spec = TestSpec();
  const std::vector<std::pair<std::vector<std::string>, std::string>> cases = {
      {{"--in", "x", "--nope"}, "unknown flag --nope"},
      {{"--in", "x", "--in", "y"}, "--in given twice"},
      {{"--in"}, "--in: missing value"},
      {{"--in", "--loud"}, "--in: missing value"},
      {{"--loud"}, "missing required flag --in"},
      {{"--in", "x", "--loud=yes"}, "--loud takes no value"},
      {{"--in", "x", "stray"}, "unexpected argument 'stray'"},
      {{"--in", "x", "-v"}, "unknown flag -v"},
  };
  for (const auto& [args, expected] : cases) {
    absl::StatusOr<ParsedArgs> parsed = ParseArgs(spec, args);
    ASSERT_FALSE(parsed.ok()) << expected;
    EXPECT_NE(parsed.status().message().find(expected), std::string::npos)
        << parsed.status().message() << " should contain " << expected;
  }
}

TEST(CliArgParser, RepeatedFlagsKeepEveryValueInOrder) {
  CommandSpec spec = TestSpec();
  spec.flags.push_back({"label", "NAME", "a label", false, /*repeated=*/true});
  absl::StatusOr<ParsedArgs> parsed =
      ParseArgs(spec, {"--label", "a", "--in", "x", "--label=b", "--label", "c"});
  ASSERT_TRUE(parsed.ok()) << parsed.status();
  EXPECT_EQ(parsed->GetAll("label"), (std::vector<std::string>{"a", "b", "c"}));
  EXPECT_EQ(parsed->Get("label"), "c");
  EXPECT_EQ(parsed->GetAll("in"), (std::vector<std::string>{"x"}));
  EXPECT_TRUE(parsed->GetAll("max-count").empty());
  EXPECT_NE(HelpText(spec).find("a label (repeatable)"), std::string::npos) << HelpText(spec);
  // A flag that is not repeatable is still refused twice.
  EXPECT_FALSE(ParseArgs(spec, {"--in", "x", "--in", "y", "--label", "a"}).ok());
}

TEST(CliArgParser, HelpSkipsRequiredFlagsAndListsEveryFlag) {
  absl::StatusOr<ParsedArgs> parsed = ParseArgs(TestSpec(), {"--help"});
  ASSERT_TRUE(parsed.ok());
  EXPECT_TRUE(parsed->help());
  const std::string help = HelpText(TestSpec());
  for (const char* flag : {"--in F", "--max-count N", "--loud", "--help", "(required)"}) {
    EXPECT_NE(help.find(flag), std::string::npos) << flag << " missing from\n" << help;
  }
}

TEST(CliArgParser, Numbers) {
  EXPECT_EQ(*ParseFiniteDouble("e", "0.25"), 0.25);
  EXPECT_EQ(*ParseFiniteDouble("e", "1e-3"), 1e-3);
  for (const char* bad : {"", "abc", "0.1x", "nan", "NaN", "inf", "-inf", "1e999", " 1"}) {
    EXPECT_FALSE(ParseFiniteDouble("e", bad).ok()) << "'" << bad << "'";
  }
  EXPECT_EQ(*ParseInteger("n", "12", 0, 100), 12);
  for (const char* bad : {"", "1.5", "x", "-1", "101", "99999999999999999999"}) {
    EXPECT_FALSE(ParseInteger("n", bad, 0, 100).ok()) << "'" << bad << "'";
  }
}

TEST(CliGrpcChannel, PortsOutsideOneTo65535AreRefusedNamingTheTarget) {
  for (const std::string target :
       {"127.0.0.1:50051", "localhost:1", "host:65535", "dns:///refiner.local:50051",
        "dns://8.8.8.8/refiner:443", "ipv4:10.0.0.1:1,10.0.0.2:2", "[::1]:50051", "ipv6:[::1]:8080",
        "unix:/tmp/socket:99999", "unix-abstract:x", "vsock:3:70000", "host:http"}) {
    EXPECT_TRUE(cli::CheckTargetPorts(target).ok()) << target;
  }
  // Without a port gRPC dialled port 0 or 443, never a tetrefine_server: a flag error.
  for (const auto& [target, host] :
       std::vector<std::pair<std::string, std::string>>{{"127.0.0.1", "127.0.0.1"},
                                                        {"refiner.local", "refiner.local"},
                                                        {"::1", "::1"},
                                                        {"[::1]", "[::1]"},
                                                        {"host:", "host:"},
                                                        {"dns:///refiner.local", "refiner.local"},
                                                        {"ipv4:10.0.0.1:1,10.0.0.2", "10.0.0.2"}}) {
    const absl::Status status = cli::CheckTargetPorts(target);
    EXPECT_TRUE(absl::IsInvalidArgument(status)) << target;
    const std::string of = host == target ? "" : "' of '" + target;
    EXPECT_TRUE(absl::StartsWith(status.message(),
                                 "--server: '" + host + of + "' has no port: write host:port"))
        << status;
  }
  for (const auto& [target, port] :
       std::vector<std::pair<std::string, std::string>>{{"127.0.0.1:70000", "70000"},
                                                        {"localhost:0", "0"},
                                                        {"host:65536", "65536"},
                                                        {"host:0050051", "0050051"},
                                                        {"dns:///refiner.local:123456", "123456"},
                                                        {"ipv4:10.0.0.1:1,10.0.0.2:99999", "99999"},
                                                        {"[::1]:65536", "65536"}}) {
    const absl::Status status = cli::CheckTargetPorts(target);
    EXPECT_TRUE(absl::IsInvalidArgument(status)) << target;
    EXPECT_EQ(status.message(),
              "--server: port " + port + " of '" + target + "' is out of range (1-65535)");
  }
}

TEST(CliJsonWriter, NestsEscapesAndWritesNullForNonFinite) {
  JsonWriter json;
  json.BeginObject();
  json.Key("a\"b");
  json.String("line\nnext\x01");
  json.Key("list");
  json.BeginArray();
  json.Int(-3);
  json.Number(0.1);
  json.Number(std::nan(""));
  json.Bool(true);
  json.BeginObject();
  json.EndObject();
  json.BeginArray();
  json.EndArray();
  json.EndArray();
  json.Key("none");
  json.Null();
  json.Field("x", 1.5);
  json.Field("n", int64_t{7});
  json.Field("s", "t");
  json.EndObject();
  EXPECT_EQ(json.Take(),
            "{\n  \"a\\\"b\": \"line\\nnext\\u0001\",\n  \"list\": [\n    -3,\n    0.1,\n"
            "    null,\n    true,\n    {},\n    []\n  ],\n  \"none\": null,\n  \"x\": 1.5,\n"
            "  \"n\": 7,\n  \"s\": \"t\"\n}\n");
}

TEST(CliFileKind, ExtensionsAndStems) {
  EXPECT_TRUE(IsVolumePath("a/b.NII.GZ"));
  EXPECT_TRUE(IsVolumePath("b.mha"));
  EXPECT_FALSE(IsVolumePath("b.vtu"));
  EXPECT_TRUE(IsMeshPath("x.Mesh"));
  EXPECT_FALSE(IsMeshPath("x.obj"));
  EXPECT_EQ(PathStem("out/brain.refined.vtu"), "out/brain.refined");
  EXPECT_EQ(PathExtension("out/brain.refined.vtu"), ".vtu");
  EXPECT_EQ(PathStem("dir.d/noext"), "dir.d/noext");
  EXPECT_EQ(FileStem("dir/cube.mesh"), "cube");
  EXPECT_EQ(FileStem(".hidden"), ".hidden");
}

// One output must not name the file another output or an input names, however it is spelled; a
// device two outputs share is fine. (A sweep wrote --stats-json over --output and over the input
// volume, exit 0.)
TEST(CliFileKind, AnOutputNamingAnotherFlagsFileIsRefused) {
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("tetrefine_same_file_" + std::to_string(getpid()));
  std::filesystem::create_directories(dir / "sub");
  std::FILE* f = std::fopen((dir / "vol.nii").c_str(), "w");
  ASSERT_NE(f, nullptr);
  std::fclose(f);
  std::filesystem::create_symlink(dir / "vol.nii", dir / "link.json");
  const std::string d = dir.string();
  const std::vector<NamedPath> others = {{"--output", d + "/sub/../out.vtu"},
                                         {"--volume", d + "/vol.nii"}};
  for (const std::string& same : {d + "/out.vtu", d + "/./out.vtu", d + "/sub/../out.vtu",
                                  d + "/vol.nii", d + "/link.json"}) {
    const absl::Status s = CheckNotTheSameFile({"--stats-json", same}, others);
    EXPECT_FALSE(s.ok()) << same;
    EXPECT_TRUE(absl::StrContains(s.message(), "--stats-json names the same file as")) << s;
  }
  EXPECT_TRUE(CheckNotTheSameFile({"--stats-json", d + "/run.json"}, others).ok());
  EXPECT_TRUE(CheckNotTheSameFile({"--stats-json", "/dev/null"}, {{"--output", "/dev/null"}}).ok());
  // Relative spellings of a file that does not exist yet.
  std::filesystem::path cwd = std::filesystem::current_path();
  std::filesystem::current_path(dir);
  EXPECT_FALSE(CheckNotTheSameFile({"--stats-json", "./new.vtu"}, {{"--output", "new.vtu"}}).ok());
  std::filesystem::current_path(cwd);
  std::filesystem::remove_all(dir);
}

// The lattice line says whether it covers every tet or a sample of them (a sample's maximum can
// be below the mesh's: an independent check found 0.2055 against 0.2606, 2026-11-25); with
// --certify, a run a limit stopped says it is not certified.
TEST(CliRefineReport, TheLatticeLineSaysSampleOrEveryTetAndCertifyWhyNot) {
  RefineResult result;
  result.stop_reason = StopReason::kMaxIterations;
  result.final_quality.count = 874585;
  result.lattice.tets_sampled = 200000;
  result.lattice.points_sampled = 33000000;
  std::string report = FormatRefineReport(result, 0.02, /*certify=*/true);
  EXPECT_TRUE(absl::StrContains(report,
                                "33000000 points in a sample of 200000 of the 874585 tets; its "
                                "max can be below the mesh's"))
      << report;
  EXPECT_TRUE(absl::StrContains(report,
                                "Not certified: the run stopped before every tet's lattice error "
                                "was within epsilon (max_iterations)"))
      << report;

  result.final_quality.count = 200000;
  result.stop_reason = StopReason::kConverged;
  result.certified_max_error = 0.019;
  report = FormatRefineReport(result, 0.02, /*certify=*/true);
  EXPECT_TRUE(absl::StrContains(report, "points in every one of the 200000 tets")) << report;
  EXPECT_TRUE(absl::StrContains(report, "Certified: lattice error at most 0.019000")) << report;
  // What it is a maximum over (an outside review read it as a bound on the whole tet).
  EXPECT_TRUE(absl::StrContains(report,
                                "(n = 8: the maximum over each tet's 165 lattice points, not a "
                                "bound between them)"))
      << report;
  EXPECT_FALSE(absl::StrContains(report, "Not certified")) << report;

  result.certified_max_error = -1.0;
  EXPECT_FALSE(absl::StrContains(FormatRefineReport(result, 0.02), "ertified"));
}

// --lattice-n 0 samples nothing: the JSON's lattice order says 0, not the default 8.
TEST(CliStatsJson, ALatticeThatSampledNothingHasOrderZero) {
  client::ClientResult reply;
  reply.result.lattice.n = 8;
  // The lattice object's first line (the JSON is indented, one field per line).
  const auto lattice_order = [&] {
    const std::string json = RefineStatsJson({}, reply);
    const size_t at = json.find("\"lattice\": {");
    return at == std::string::npos ? json : json.substr(at, json.find(',', at) - at);
  };
  EXPECT_TRUE(absl::StrContains(lattice_order(), "\"n\": 0")) << lattice_order();
  reply.result.lattice.tets_sampled = 10;
  EXPECT_TRUE(absl::StrContains(lattice_order(), "\"n\": 8")) << lattice_order();
}

TEST(CliTextTable, AlignsColumns) {
  EXPECT_EQ(FormatTable({{"a", "bb"}, {"ccc", "d"}}), "    a  bb\n  ccc   d\n");
  EXPECT_EQ(FormatTable({{"a", "bb"}, {"ccc", "d"}}, true), "  a    bb\n  ccc   d\n");
}

GridMeshOptions Options(int64_t block, std::optional<double> threshold = std::nullopt,
                        int64_t max_tets = 50'000'000) {
  GridMeshOptions options;
  options.block = block;
  options.mask_threshold = threshold;
  options.max_tets = max_tets;
  return options;
}

// Every tet positive, faces conformal, the mesh fills the grid's box exactly.
void ExpectGoodGridMesh(const Mesh& mesh, double box_volume) {
  double total = 0.0;
  for (const Tet& t : mesh.tets) {
    const double v6 =
        SignedVolume6(mesh.points[t[0]], mesh.points[t[1]], mesh.points[t[2]], mesh.points[t[3]]);
    ASSERT_GT(v6, 0.0);
    total += v6 / 6.0;
  }
  EXPECT_NEAR(total, box_volume, 1e-9 * box_volume);
  EXPECT_TRUE(CheckFaces(mesh.points, mesh.tets).ok()) << CheckFaces(mesh.points, mesh.tets);
  const MeshReport report = AnalyzeMesh(mesh);
  EXPECT_TRUE(report.valid());
  EXPECT_EQ(report.unused_vertices, 0);
}

TEST(CliGridMesher, FiveTetsPerCellConformalWithRemainderBlocks) {
  // 8 x 6 x 5 samples: cells of 3 leave remainders of 1, 2 and 1 voxels.
  const Volume volume = clitest::BumpVolume({8, 6, 5}, {-1.0, 2.0, 0.5}, {0.5, 1.0, 2.0});
  for (int64_t block : {1, 2, 3, 7, 100}) {
    SCOPED_TRACE(block);
    absl::StatusOr<GridMesh> grid = MeshVolumeGrid(volume, Options(block));
    ASSERT_TRUE(grid.ok()) << grid.status();
    const auto cells = [&](int64_t d) { return (d - 1 + block - 1) / block; };
    EXPECT_EQ(grid->cells, cells(8) * cells(6) * cells(5));
    EXPECT_EQ(grid->cells_kept, grid->cells);
    EXPECT_EQ(static_cast<int64_t>(grid->mesh.tets.size()), 5 * grid->cells);
    ExpectGoodGridMesh(grid->mesh, 3.5 * 5.0 * 8.0);
    // Vertices sit on samples and carry them.
    for (size_t v = 0; v < grid->mesh.points.size(); ++v) {
      ASSERT_DOUBLE_EQ(grid->mesh.values[v], volume.Sample(grid->mesh.points[v]));
    }
  }
}

TEST(CliGridMesher, MaskKeepsCellsWithAllCornersAboveThreshold) {
  // Value = x index: only cells with i >= 2 have all corners >= 2.
  std::vector<double> values;
  for (int k = 0; k < 3; ++k)
    for (int j = 0; j < 3; ++j)
      for (int i = 0; i < 5; ++i) values.push_back(i);
  const Volume volume = *Volume::FromDoubles({{5, 3, 3}, {0, 0, 0}, {1, 1, 1}}, values);
  absl::StatusOr<GridMesh> grid = MeshVolumeGrid(volume, Options(1, 2.0));
  ASSERT_TRUE(grid.ok()) << grid.status();
  EXPECT_EQ(grid->cells, 16);
  EXPECT_EQ(grid->cells_kept, 8);
  EXPECT_EQ(grid->mesh.points.size(), 27u);  // unused vertices at x = 0, 1 are dropped
  for (const Vec3& p : grid->mesh.points) EXPECT_GE(p[0], 2.0);
  ExpectGoodGridMesh(grid->mesh, 8.0);

  absl::StatusOr<GridMesh> none = MeshVolumeGrid(volume, Options(1, 10.0));
  ASSERT_FALSE(none.ok());
  EXPECT_NE(none.status().message().find("no cell"), std::string::npos) << none.status();
}

TEST(CliGridMesher, RefusesHugeGrids) {
  const Volume volume = clitest::BumpVolume({11, 11, 11}, {0, 0, 0}, {1, 1, 1});
  EXPECT_FALSE(MeshVolumeGrid(volume, Options(1, std::nullopt, 4999)).ok());
  EXPECT_TRUE(MeshVolumeGrid(volume, Options(1, std::nullopt, 5000)).ok());
}

TEST(CliMeshPlacement, FitFillsTheBoxLessAVoxelAndKeepsOrientation) {
  const Volume volume = clitest::BumpVolume({9, 11, 6}, {-4.0, 10.0, 0.0}, {1.0, 2.0, 0.5});
  Mesh mesh = testing::FiveTetMesh({-0.5, -0.5, -0.5}, {0.5, 0.5, 0.5}, {2, 2, 2});
  EXPECT_GE(FirstVertexOutside(volume, mesh), 0);
  ASSERT_TRUE(FitMeshToVolume(volume, &mesh).ok());
  EXPECT_EQ(FirstVertexOutside(volume, mesh), -1);
  const MeshReport report = AnalyzeMesh(mesh);
  EXPECT_TRUE(report.valid());
  const Box want = {Vec3{-3.0, 12.0, 0.5}, Vec3{3.0, 28.0, 2.0}};
  EXPECT_EQ(report.bounding_box, want);

  Mesh flat;
  flat.points = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}};
  flat.tets = {{0, 1, 2, 3}};
  EXPECT_FALSE(FitMeshToVolume(volume, &flat).ok());

  // A vertex no tet uses (Gmsh -save_all keeps geometry points) does not shrink the fit: the
  // tets fill the same box as without it, and it is clamped onto that box.
  Mesh stray = testing::FiveTetMesh({-0.5, -0.5, -0.5}, {0.5, 0.5, 0.5}, {2, 2, 2});
  stray.points.push_back({5.0, 5.0, 5.0});
  ASSERT_TRUE(FitMeshToVolume(volume, &stray).ok());
  EXPECT_EQ(FirstVertexOutside(volume, stray), -1);
  EXPECT_EQ(AnalyzeMesh(stray).bounding_box, want);
  EXPECT_EQ(stray.points.back(), want[1]);
}

// A point outside an oblique grid can lie inside the grid's world bounding box: the message then
// gives its grid index against the grid's, not a box that holds it (an outside review, 2026-11-28).
TEST(CliMeshPlacement, WhereOutsideNamesTheGridOfAnObliqueVolume) {
  const Volume aligned = clitest::BumpVolume({9, 11, 6}, {-4.0, 10.0, 0.0}, {1.0, 2.0, 0.5});
  EXPECT_EQ(WhereOutside(aligned, {10, 11, 1}),
            "at (10, 11, 1) mm; the volume spans [-4, 4] x [10, 30] x [0, 2.5] mm");
  GridGeometry grid{{5, 5, 3}, {0, 0, 0}, {1, 1, 1}};
  grid.direction = {0.6, -0.8, 0.0, 0.8, 0.6, 0.0, 0.0, 0.0, 1.0};  // a rotation about z
  const Volume oblique = *Volume::FromDoubles(grid, std::vector<double>(75, 1.0));
  const Box bounds = VolumeWorldBox(oblique);
  const Vec3 corner = {bounds[0][0] + 0.1, bounds[0][1] + 0.1, 1.0};  // in the box, off the grid
  ASSERT_FALSE(oblique.Contains(oblique.ContinuousIndex(corner)));
  const std::string where = WhereOutside(oblique, corner);
  EXPECT_TRUE(absl::StrContains(where,
                                "; the volume's oblique grid spans index [0, 4] x [0, 4] x "
                                "[0, 2]"))
      << where;
  EXPECT_TRUE(absl::StrContains(where, ", grid index (")) << where;
}

TEST(CliMeshReport, FindsDuplicatesInvertedTetsAndOverusedFaces) {
  const Mesh good = testing::FiveTetMesh({0, 0, 0}, {1, 1, 1}, {2, 1, 1});
  const MeshReport ok = AnalyzeMesh(good);
  EXPECT_TRUE(ok.valid());
  EXPECT_NEAR(ok.volume, 1.0, 1e-12);
  EXPECT_NEAR(ok.boundary_area, 6.0, 1e-12);
  EXPECT_EQ(ok.boundary_faces, 20);

  Mesh inverted = good;
  std::swap(inverted.tets[3][2], inverted.tets[3][3]);
  MeshReport r = AnalyzeMesh(inverted);
  EXPECT_FALSE(r.valid());
  EXPECT_EQ(r.inverted_tets, 1);
  EXPECT_EQ(r.first_inverted, 3);

  // Three tets on one triangle: one below it, two above.
  Mesh triple;
  triple.points = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0.2, 0.2, -1}, {0.2, 0.2, 1}, {0.3, 0.1, 2}};
  triple.tets = {{0, 1, 2, 4}, {0, 2, 1, 3}, {0, 1, 2, 5}};
  r = AnalyzeMesh(triple);
  EXPECT_EQ(r.inverted_tets, 0);
  EXPECT_FALSE(r.faces.ok());
  EXPECT_FALSE(r.valid());

  // An unused copy of a vertex is inert (refine carries it through): valid, and counted as
  // unused. A used copy is a crack.
  Mesh duplicate = good;
  duplicate.points.push_back(duplicate.points[4]);
  r = AnalyzeMesh(duplicate);
  EXPECT_EQ(r.duplicate_vertices, 0);
  EXPECT_EQ(r.unused_vertices, 1);
  EXPECT_EQ(r.valid(), AnalyzeMesh(good).valid());
  // The first tet with vertex 4 takes the copy instead.
  const auto with4 = std::find_if(duplicate.tets.begin(), duplicate.tets.end(), [](const Tet& t) {
    return std::find(t.begin(), t.end(), 4u) != t.end();
  });
  ASSERT_NE(with4, duplicate.tets.end());
  *std::find(with4->begin(), with4->end(), 4u) = static_cast<uint32_t>(duplicate.points.size() - 1);
  r = AnalyzeMesh(duplicate);
  EXPECT_EQ(r.duplicate_vertices, 1);
  EXPECT_EQ(r.first_duplicate[0], 4);
  EXPECT_FALSE(r.valid());
}

}  // namespace
}  // namespace tetrefine::cli

// The CLI's channels ping every 30 s while a call is silent, with no limit on pings without data:
// gRPC's default of two let a call that had been silent for a minute wait for ever on a server
// that then froze (an outside review, 2026-11-29).
TEST(CliChannel, KeepalivePingsHaveNoLimitWithoutData) {
  const grpc::ChannelArguments args = tetrefine::cli::ChannelArgumentsForCli();
  const grpc_channel_args c = args.c_channel_args();
  std::map<std::string, int> ints;
  for (size_t i = 0; i < c.num_args; ++i) {
    if (c.args[i].type == GRPC_ARG_INTEGER) ints[c.args[i].key] = c.args[i].value.integer;
  }
  EXPECT_EQ(ints[GRPC_ARG_KEEPALIVE_TIME_MS], 30'000);
  EXPECT_EQ(ints[GRPC_ARG_KEEPALIVE_TIMEOUT_MS], 20'000);
  ASSERT_EQ(ints.count(GRPC_ARG_HTTP2_MAX_PINGS_WITHOUT_DATA), 1u);
  EXPECT_EQ(ints[GRPC_ARG_HTTP2_MAX_PINGS_WITHOUT_DATA], 0);
}
