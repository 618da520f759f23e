// `tetrefine refine --server` and `tetrefine health` against a real tetrefine_server process on a
// loopback port.

#include <algorithm>
#include <array>
#include <string>
#include <vector>

#include "absl/strings/match.h"
#include "absl/strings/str_cat.h"
#include "client/cli/convergence_stats.h"
#include "client/io/mesh_io.h"
#include "gtest/gtest.h"
#include "sharding/halo_parts.h"
#include "tests/cli/cli_test_util.h"
#include "tests/io/io_test_util.h"
#include "tests/support/geometry.h"
#include "tests/support/mesh_checks.h"

namespace tetrefine::clitest {
namespace {

using io::iotest::ScratchDir;

class CliServer : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    absl::StatusOr<std::unique_ptr<ServerProcess>> server = ServerProcess::Start({"--threads=2"});
    if (server.ok()) {
      server_ = server->release();
    } else {
      start_error_ = new std::string(server.status().ToString());
    }
  }
  static void TearDownTestSuite() {
    delete server_;
    server_ = nullptr;
    delete start_error_;
    start_error_ = nullptr;
  }
  void SetUp() override {
    ASSERT_NE(server_, nullptr) << *start_error_;
    volume_ = dir_.File("bump.nii");
    mesh_ = dir_.File("grid.vtu");
    WriteVolume(volume_, BumpVolume({9, 9, 9}, {0.0, 0.0, 0.0}, {1.0, 1.0, 1.0}));
    WriteMeshFile(mesh_, testing::FiveTetMesh({1, 1, 1}, {7, 7, 7}, {2, 2, 2}));
  }

  static ServerProcess* server_;
  static std::string* start_error_;
  ScratchDir dir_;
  std::string volume_;
  std::string mesh_;
};

ServerProcess* CliServer::server_ = nullptr;
std::string* CliServer::start_error_ = nullptr;

TEST_F(CliServer, RemoteRefineGivesTheEmbeddedResult) {
  const std::string remote = dir_.File("remote.vtu");
  const std::string embedded = dir_.File("embedded.vtu");
  const std::vector<std::string> common = {"refine", "--volume",  volume_, "--mesh",
                                           mesh_,    "--epsilon", "0.05"};
  std::vector<std::string> args = common;
  args.insert(args.end(), {"--server", server_->target(), "--output", remote});
  const ProcessResult run_remote = RunTetrefine(args);
  ASSERT_EQ(run_remote.exit_code, 0) << run_remote.err;
  EXPECT_TRUE(absl::StrContains(run_remote.err, "server " + server_->target())) << run_remote.err;
  args = common;
  args.insert(args.end(), {"--output", embedded});
  const ProcessResult run_embedded = RunTetrefine(args);
  ASSERT_EQ(run_embedded.exit_code, 0) << run_embedded.err;

  absl::StatusOr<io::MeshFile> a = io::ReadMesh(remote);
  absl::StatusOr<io::MeshFile> b = io::ReadMesh(embedded);
  ASSERT_TRUE(a.ok() && b.ok());
  EXPECT_EQ(a->mesh.points, b->mesh.points);
  EXPECT_EQ(a->mesh.tets, b->mesh.tets);
  EXPECT_EQ(a->tet_iteration, b->tet_iteration);
}

TEST_F(CliServer, ShardedOverTwoServersGivesTheEmbeddedResult) {
  absl::StatusOr<std::unique_ptr<ServerProcess>> started = ServerProcess::Start({"--threads=1"});
  ASSERT_TRUE(started.ok()) << started.status();
  const ServerProcess& second = **started;
  const std::string embedded = dir_.File("embedded.vtu");
  // The paper's scheme: parts refined to the end in one call each.
  const std::vector<std::string> common = {"refine",    "--volume", volume_,    "--mesh", mesh_,
                                           "--epsilon", "0.05",     "--scheme", "paper"};
  std::vector<std::string> args = common;
  args.insert(args.end(), {"--output", embedded});
  ASSERT_EQ(RunTetrefine(args).exit_code, 0);
  absl::StatusOr<io::MeshFile> want = io::ReadMesh(embedded);
  ASSERT_TRUE(want.ok());
  for (const char* shards : {"2", "3"}) {
    const std::string sharded = dir_.File(std::string("sharded") + shards + ".vtu");
    args = common;
    args.insert(args.end(), {"--server", server_->target() + "," + second.target(), "--shards",
                             shards, "--output", sharded});
    const ProcessResult run = RunTetrefine(args);
    ASSERT_EQ(run.exit_code, 0) << run.err;
    EXPECT_TRUE(absl::StrContains(run.err, std::string(shards) + " shards over 2 servers"))
        << run.err;
    EXPECT_TRUE(absl::StrContains(run.err, std::string("cutting the mesh into ") + shards +
                                               " parts and sending each to its server"))
        << run.err;
    absl::StatusOr<io::MeshFile> got = io::ReadMesh(sharded);
    ASSERT_TRUE(got.ok());
    EXPECT_EQ(testing::GeometricTets(got->mesh), testing::GeometricTets(want->mesh))
        << shards << " shards";
  }
  // The default scheme reads neighbouring tets: sharded one iteration at a time with halos, the
  // same mesh again.
  const std::vector<std::string> default_scheme = {"refine", "--volume",  volume_, "--mesh",
                                                   mesh_,    "--epsilon", "0.05"};
  args = default_scheme;
  args.insert(args.end(), {"--output", dir_.File("embedded_default.vtu")});
  ASSERT_EQ(RunTetrefine(args).exit_code, 0);
  args = default_scheme;
  args.insert(args.end(), {"--server", server_->target() + "," + second.target(), "--output",
                           dir_.File("sharded_default.vtu")});
  const ProcessResult run = RunTetrefine(args);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  // Its parts are cut anew each iteration, fewer where their halos would overlap (on this small
  // mesh, one): the progress line said "into 2 parts" (an outside review, 2026-11-28).
  EXPECT_TRUE(
      absl::StrContains(run.err, absl::StrCat("cutting each iteration's mesh into up to 2 "
                                              "parts (fewer where their ",
                                              sharding::kHaloRings, "-ring halos would overlap")))
      << run.err;
  absl::StatusOr<io::MeshFile> want_default = io::ReadMesh(dir_.File("embedded_default.vtu"));
  absl::StatusOr<io::MeshFile> got_default = io::ReadMesh(dir_.File("sharded_default.vtu"));
  ASSERT_TRUE(want_default.ok() && got_default.ok());
  EXPECT_EQ(testing::GeometricTets(got_default->mesh), testing::GeometricTets(want_default->mesh));
  EXPECT_NE(testing::GeometricTets(want_default->mesh), testing::GeometricTets(want->mesh))
      << "the default scheme gave the paper's mesh: this does not test it";
  // Sharding merges finished parts, so per-iteration meshes cannot be streamed.
  args = common;
  args.insert(args.end(), {"--server", server_->target() + "," + second.target(),
                           "--every-iteration", "--output", dir_.File("x.vtu")});
  const ProcessResult refused = RunTetrefine(args);
  EXPECT_EQ(refused.exit_code, 2);
  EXPECT_TRUE(absl::StartsWith(refused.err, "tetrefine: --every-iteration: ")) << refused.err;
}

// Without --max-tets a sharded run's budget is the smallest output limit of its servers, in
// whatever order they are listed: it was the smallest limit a part's server reported, and this
// small mesh's iterations each go to the first address, so swapping a server with a small limit
// and one with the default changed the result (an outside review). Both orders give the
// embedded run with that limit as --max-tets.
TEST_F(CliServer, AShardedRunsBudgetIsTheSmallestServerLimitInAnyOrder) {
  const std::vector<std::string> common = {"refine", "--volume",  volume_, "--mesh",
                                           mesh_,    "--epsilon", "0.02",  "--quiet"};
  std::vector<std::string> args = common;
  args.insert(args.end(),
              {"--output", dir_.File("free.vtu"), "--stats-json", dir_.File("free.json")});
  ASSERT_EQ(RunTetrefine(args).exit_code, 0);
  absl::StatusOr<cli::ConvergenceRun> free_run = cli::ReadConvergenceRun(dir_.File("free.json"));
  ASSERT_TRUE(free_run.ok()) << free_run.status();
  ASSERT_GE(free_run->tets.size(), 4u) << "the case should take several iterations";
  // A limit the first iteration fits and the second does not.
  const int64_t limit = free_run->tets[1] + 1;
  absl::StatusOr<std::unique_ptr<ServerProcess>> started =
      ServerProcess::Start({"--threads=1", absl::StrCat("--max_output_tets=", limit)});
  ASSERT_TRUE(started.ok()) << started.status();
  const ServerProcess& small = **started;
  args = common;
  args.insert(args.end(), {"--max-tets", absl::StrCat(limit), "--output", dir_.File("want.vtu")});
  ASSERT_EQ(RunTetrefine(args).exit_code, 0);
  absl::StatusOr<io::MeshFile> want = io::ReadMesh(dir_.File("want.vtu"));
  ASSERT_TRUE(want.ok());
  ASSERT_EQ(want->mesh.tets.size(), static_cast<size_t>(free_run->tets[1]));
  for (const std::string& servers :
       {server_->target() + "," + small.target(), small.target() + "," + server_->target()}) {
    args = common;
    args.insert(args.end(), {"--server", servers, "--shards", "2", "--output", dir_.File("s.vtu")});
    const ProcessResult run = RunTetrefine(args);
    ASSERT_EQ(run.exit_code, 0) << run.err;
    EXPECT_TRUE(absl::StrContains(run.out, "Stopped after 1 iteration: tet_budget")) << run.out;
    absl::StatusOr<io::MeshFile> got = io::ReadMesh(dir_.File("s.vtu"));
    ASSERT_TRUE(got.ok());
    EXPECT_EQ(testing::GeometricTets(got->mesh), testing::GeometricTets(want->mesh)) << servers;
  }
}

// A replica that is down is worked around, and the operator is told, even with --quiet (a CLI
// sweep found the retry silent). Each iteration's line comes as it is merged.
TEST_F(CliServer, AShardedRunSaysWhichServerFailedAndWhereThePartWent) {
  const std::string dead = absl::StrCat("127.0.0.1:", ClosedPort());
  const std::vector<std::string> common = {"refine", "--volume",  volume_, "--mesh",
                                           mesh_,    "--epsilon", "0.05"};
  std::vector<std::string> args = common;
  args.insert(args.end(), {"--output", dir_.File("embedded_retry.vtu")});
  ASSERT_EQ(RunTetrefine(args).exit_code, 0);
  args = common;
  args.insert(args.end(), {"--server", server_->target() + "," + dead, "--output",
                           dir_.File("retried.vtu"), "--quiet"});
  ProcessResult run = RunTetrefine(args);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  // Once, when the servers are asked for their limits; it is then left out of the run (it was
  // tried, and warned about, again for each part in every iteration).
  EXPECT_TRUE(
      absl::StartsWith(run.err, "tetrefine: warning: " + dead + " is unreachable (UNAVAILABLE: "))
      << run.err;
  EXPECT_TRUE(absl::StrContains(run.err, "); its parts go to the others\n")) << run.err;
  EXPECT_EQ(SplitLines(run.err).size(), 1u) << run.err;
  absl::StatusOr<io::MeshFile> want = io::ReadMesh(dir_.File("embedded_retry.vtu"));
  absl::StatusOr<io::MeshFile> got = io::ReadMesh(dir_.File("retried.vtu"));
  ASSERT_TRUE(want.ok() && got.ok());
  EXPECT_EQ(testing::GeometricTets(got->mesh), testing::GeometricTets(want->mesh));
  // Without --quiet the iterations are reported one by one, before the parts are measured.
  args.pop_back();
  run = RunTetrefine(args);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const size_t first = run.err.find("tetrefine: iteration 1: ");
  const size_t measured = run.err.find("tetrefine: parts refined and measured");
  ASSERT_NE(first, std::string::npos) << run.err;
  EXPECT_LT(first, measured) << run.err;
}

// A server that refuses one of the request's options refuses it again: the sharded run fails at
// once with the refusal, no retry warning (an outside review saw eight, the server then marked
// down). Addresses may have spaces after the commas.
TEST_F(CliServer, AShardedRunDoesNotRetryARefusedOptionAndTakesSpacedAddresses) {
  absl::StatusOr<std::unique_ptr<ServerProcess>> started =
      ServerProcess::Start({"--threads=1", "--max_iterations=3"});
  ASSERT_TRUE(started.ok()) << started.status();
  const ServerProcess& strict = **started;
  const std::vector<std::string> common = {"refine", "--volume",  volume_, "--mesh",
                                           mesh_,    "--epsilon", "0.05",  "--scheme",
                                           "paper",  "--shards",  "3",     "--quiet"};
  std::vector<std::string> args = common;
  args.insert(args.end(), {"--server", strict.target(), "--output", dir_.File("refused.vtu")});
  ProcessResult run = RunTetrefine(args);
  EXPECT_EQ(run.exit_code, 1) << run.err;
  EXPECT_TRUE(absl::StrContains(run.err, "options.max_iterations: 32 exceeds this server's limit"))
      << run.err;
  EXPECT_FALSE(absl::StrContains(run.err, "retrying")) << run.err;
  EXPECT_EQ(SplitLines(run.err).size(), 1u) << run.err;
  // The same run within its limit, over both servers written with a space after the comma:
  // both are used, none is reported unreachable.
  args = common;
  args.insert(args.end(),
              {"--max-iterations", "3", "--server", server_->target() + ", " + strict.target(),
               "--output", dir_.File("spaced.vtu")});
  args.erase(std::find(args.begin(), args.end(), "--quiet"));
  run = RunTetrefine(args);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_TRUE(absl::StrContains(run.err, "3 shards over 2 servers")) << run.err;
  EXPECT_FALSE(absl::StrContains(run.err, "unreachable")) << run.err;
}

// A server that runs one refinement at a time gets one part at a time: the others wait in the
// client, not in its queue, where they timed out (RESOURCE_EXHAUSTED), were retried and failed
// the run (an outside review: --max_concurrent 1 --queue_seconds 1, four parts).
TEST_F(CliServer, ASerialServerGetsOnePartAtATime) {
  absl::StatusOr<std::unique_ptr<ServerProcess>> started =
      ServerProcess::Start({"--threads=1", "--max_concurrent=1", "--queue_seconds=0.02"});
  ASSERT_TRUE(started.ok()) << started.status();
  const ServerProcess& serial = **started;
  const std::string mesh = dir_.File("finer.vtu");
  WriteMeshFile(mesh, testing::FiveTetMesh({1, 1, 1}, {7, 7, 7}, {6, 6, 6}));
  const std::vector<std::string> args = {
      "refine",    "--volume", volume_,         "--mesh",   mesh,
      "--epsilon", "0.005",    "--scheme",      "paper",    "--shards",
      "4",         "--server", serial.target(), "--output", dir_.File("serial.vtu")};
  const ProcessResult run = RunTetrefine(args);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_FALSE(absl::StrContains(run.err, "retrying")) << run.err;
  EXPECT_FALSE(absl::StrContains(run.err, "RESOURCE_EXHAUSTED")) << run.err;
}

TEST_F(CliServer, ServerSideValidationErrorNamesTheMesh) {
  // Two tets above one triangle: a face in three tets, which only the service's check finds.
  Mesh bad;
  bad.points = {{2, 2, 2}, {4, 2, 2}, {2, 4, 2}, {2.5, 2.5, 1}, {2.5, 2.5, 3}, {2.6, 2.4, 4}};
  bad.tets = {{0, 1, 2, 4}, {0, 2, 1, 3}, {0, 1, 2, 5}};
  const std::string path = dir_.File("triple.vtu");
  WriteMeshFile(path, bad);
  const std::string out = dir_.File("never.vtu");
  const ProcessResult run =
      RunTetrefine({"refine", "--volume", volume_, "--mesh", path, "--epsilon", "0.1", "--server",
                    server_->target(), "--output", out, "--quiet"});
  EXPECT_EQ(run.exit_code, 2) << run.err;
  ASSERT_EQ(SplitLines(run.err).size(), 1u) << run.err;
  EXPECT_TRUE(absl::StartsWith(run.err, "tetrefine: " + path + ": ")) << run.err;
  EXPECT_FALSE(FileExists(out));
}

TEST_F(CliServer, HealthIsServing) {
  for (const char* service : {"", "tetrefine.v1.Refiner"}) {
    const ProcessResult run =
        RunTetrefine({"health", "--server", server_->target(), "--service", service});
    EXPECT_EQ(run.exit_code, 0) << service << ": " << run.err;
    EXPECT_EQ(run.out, "SERVING\n");
  }
}

TEST_F(CliServer, HealthOfAnUnknownServiceFails) {
  const ProcessResult run =
      RunTetrefine({"health", "--server", server_->target(), "--service", "no.such.Service"});
  EXPECT_EQ(run.exit_code, 1) << run.err;
  EXPECT_EQ(SplitLines(run.err).size(), 1u) << run.err;
}

TEST(CliHealth, ClosedPortFailsQuickly) {
  const std::string address = "127.0.0.1:" + std::to_string(ClosedPort());
  const ProcessResult run =
      RunTetrefine({"health", "--server", address, "--timeout", "2"}, "", /*timeout_seconds=*/30);
  EXPECT_EQ(run.exit_code, 1) << run.err;
  EXPECT_LT(run.seconds, 10.0);
  ASSERT_EQ(SplitLines(run.err).size(), 1u) << run.err;
  EXPECT_TRUE(absl::StrContains(run.err, address)) << run.err;
}

TEST(CliHealth, RefineAgainstAClosedPortFailsWithoutOutput) {
  ScratchDir dir;
  const std::string volume = dir.File("v.nii");
  const std::string mesh = dir.File("m.vtu");
  WriteVolume(volume, BumpVolume({5, 5, 5}, {0, 0, 0}, {1, 1, 1}));
  WriteMeshFile(mesh, testing::FiveTetMesh({0, 0, 0}, {4, 4, 4}, {1, 1, 1}));
  const std::string out = dir.File("out.vtu");
  const std::string address = "127.0.0.1:" + std::to_string(ClosedPort());
  const ProcessResult run = RunTetrefine({"refine", "--volume", volume, "--mesh", mesh, "--epsilon",
                                          "0.1", "--server", address, "--output", out, "--quiet"},
                                         "", /*timeout_seconds=*/60);
  EXPECT_EQ(run.exit_code, 1) << run.err;
  EXPECT_TRUE(absl::StrContains(run.err, "UNAVAILABLE")) << run.err;
  EXPECT_FALSE(FileExists(out));
}

TEST(CliServerToken, TheTokenFileIsSentToAServerThatNeedsOne) {
  ScratchDir dir;
  io::iotest::WriteBytes(dir.File("tokens.txt"), "alice token-of-alice-0123456789\n");
  io::iotest::WriteBytes(dir.File("alice.token"), "token-of-alice-0123456789\n");
  io::iotest::WriteBytes(dir.File("mallory.token"), "token-of-mallory-012345678\n");
  absl::StatusOr<std::unique_ptr<ServerProcess>> started =
      ServerProcess::Start({"--token_file=" + dir.File("tokens.txt"), "--threads=2"});
  ASSERT_TRUE(started.ok()) << started.status();
  ServerProcess& server = **started;
  const std::string volume = dir.File("v.nii");
  const std::string mesh = dir.File("m.vtu");
  WriteVolume(volume, BumpVolume({9, 9, 9}, {0, 0, 0}, {1, 1, 1}));
  WriteMeshFile(mesh, testing::FiveTetMesh({1, 1, 1}, {7, 7, 7}, {2, 2, 2}));
  const std::vector<std::string> common = {
      "refine",    "--volume", volume,     "--mesh",        mesh,
      "--epsilon", "0.05",     "--server", server.target(), "--quiet"};
  auto refine = [&](std::vector<std::string> extra) {
    std::vector<std::string> args = common;
    args.insert(args.end(), extra.begin(), extra.end());
    return RunTetrefine(args);
  };
  const ProcessResult without = refine({"--output", dir.File("a.vtu")});
  EXPECT_EQ(without.exit_code, 1) << without.err;
  EXPECT_TRUE(absl::StrContains(without.err, "--token-file")) << without.err;
  const ProcessResult wrong =
      refine({"--token-file", dir.File("mallory.token"), "--output", dir.File("b.vtu")});
  EXPECT_EQ(wrong.exit_code, 1) << wrong.err;
  EXPECT_TRUE(absl::StrContains(wrong.err, "not one this server knows")) << wrong.err;
  const ProcessResult right =
      refine({"--token-file", dir.File("alice.token"), "--output", dir.File("c.vtu")});
  EXPECT_EQ(right.exit_code, 0) << right.err;
  EXPECT_TRUE(FileExists(dir.File("c.vtu")));
  const ProcessResult missing =
      refine({"--token-file", dir.File("nonexistent"), "--output", dir.File("d.vtu")});
  EXPECT_EQ(missing.exit_code, 2) << missing.err;
  EXPECT_TRUE(absl::StrContains(missing.err, "--token-file")) << missing.err;
}

TEST(CliServerChunks, TheUploadFitsTheServersMessageLimit) {
  // 48^3 float64 voxels (864 KiB) would be one 864 KiB message at the default chunk size; this
  // server takes 64 KiB at most and says so through GetServerInfo.
  absl::StatusOr<std::unique_ptr<ServerProcess>> started =
      ServerProcess::Start({"--max_message_bytes=65536", "--threads=2"});
  ASSERT_TRUE(started.ok()) << started.status();
  ServerProcess& server = **started;
  ScratchDir dir;
  const std::string volume = dir.File("v.nii");
  const std::string mesh = dir.File("m.vtu");
  WriteVolume(volume, BumpVolume({48, 48, 48}, {0, 0, 0}, {1, 1, 1}));
  WriteMeshFile(mesh, testing::FiveTetMesh({1, 1, 1}, {46, 46, 46}, {3, 3, 3}));
  const ProcessResult run = RunTetrefine(
      {"refine", "--volume", volume, "--mesh", mesh, "--epsilon", "0.1", "--max-iterations", "1",
       "--server", server.target(), "--output", dir.File("out.vtu"), "--quiet"});
  EXPECT_EQ(run.exit_code, 0) << run.err;
}

}  // namespace
}  // namespace tetrefine::clitest
