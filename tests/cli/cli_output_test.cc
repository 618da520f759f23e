// What `tetrefine refine` and `tetrefine mesh` write and say while they work: the encoding flags
// (--vtu-compression, --vtu-encoding, --binary, --ascii) give files that this library and an
// independent reader (python3 meshio, VTK 9) read back with the same tets and labels; bad values
// are refused naming the flag; refine reports every phase on stderr, in order, unless --quiet.

#include <sys/stat.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <csignal>
#include <cstdint>
#include <cstdlib>
#include <fstream>
#include <memory>
#include <optional>
#include <random>
#include <set>
#include <sstream>
#include <string>
#include <thread>
#include <tuple>
#include <vector>

#include "absl/strings/match.h"
#include "absl/strings/str_cat.h"
#include "client/cli/progress.h"
#include "client/io/mesh_io.h"
#include "gtest/gtest.h"
#include "tests/cli/cli_test_util.h"
#include "tests/io/io_test_util.h"
#include "tests/support/child_process.h"
#include "tests/support/geometry.h"

namespace tetrefine::clitest {
namespace {

using cli::FormatBytes;
using cli::FormatCount;
using cli::FormatSeconds;
using io::iotest::kPython;
using io::iotest::ReadBytes;
using io::iotest::ScratchDir;

// An encoding to try: the flags, the extension, and a piece of the file's text that shows the
// flag took effect (so a flag that is parsed but ignored fails).
struct Variant {
  std::string extension;
  std::vector<std::string> flags;
  std::string marker;
};

std::vector<Variant> Variants() {
  std::vector<Variant> all = {
      {".vtu", {}, "compressor=\"vtkZLibDataCompressor\""},  // ParaView's default
      {".vtu", {"--vtu-encoding", "ascii"}, "format=\"ascii\""},
      {".msh", {}, "\n4.1 1 8\n"},  // binary by default
      {".msh", {"--binary"}, "\n4.1 1 8\n"},
      {".msh", {"--ascii"}, "\n4.1 0 8\n"},
      {".vtk", {}, "\nBINARY\n"},
      {".vtk", {"--ascii"}, "\nASCII\n"},
  };
  for (const char* encoding : {"appended", "base64"}) {
    for (const auto& [name, attribute] :
         std::vector<std::pair<std::string, std::string>>{{"none", ""},
                                                          {"zlib", "vtkZLibDataCompressor"},
                                                          {"lzma", "vtkLZMADataCompressor"},
                                                          {"lz4", "vtkLZ4DataCompressor"}}) {
      Variant v{".vtu", {"--vtu-encoding", encoding, "--vtu-compression", name}, ""};
      v.marker = attribute.empty() ? std::string(encoding) == "appended" ? "encoding=\"raw\""
                                                                         : "format=\"binary\""
                                   : absl::StrCat("compressor=\"", attribute, "\"");
      all.push_back(v);
    }
  }
  return all;
}

std::string Describe(const Variant& v) {
  std::string text = v.extension;
  for (const std::string& flag : v.flags) absl::StrAppend(&text, " ", flag);
  return text;
}

// The (tet, label) pairs of a mesh, sorted: Gmsh files group tets by physical group, so only
// the multiset is the same across formats.
std::vector<std::tuple<Tet, int32_t>> TetLabelPairs(const io::MeshFile& file) {
  std::vector<std::tuple<Tet, int32_t>> pairs;
  for (size_t t = 0; t < file.mesh.tets.size(); ++t) {
    pairs.emplace_back(file.mesh.tets[t], file.mesh.labels.empty() ? 0 : file.mesh.labels[t]);
  }
  std::sort(pairs.begin(), pairs.end());
  return pairs;
}

// What the independent readers print: tets, the sum of all vertex indices, the sum of labels
// and the sum of label * (index sum of its tet), which ties each label to its tet whatever the
// order. Passed to python3 -c (no single quotes). argv: reader (meshio|vtk), path, label key.
constexpr char kReaderScript[] = R"(
import sys, warnings
warnings.simplefilter("ignore")
reader, path, key = sys.argv[1], sys.argv[2], sys.argv[3]
if reader == "meshio":
    import meshio, numpy as np
    m = meshio.read(path)
    tets, labels = [], []
    for i, c in enumerate(m.cells):
        if c.type == "tetra":
            tets.append(np.asarray(c.data, dtype=np.int64))
            labels.append(np.asarray(m.cell_data[key][i]).astype(np.int64).reshape(-1))
    t = np.concatenate(tets)
    l = np.concatenate(labels)
else:
    import vtk
    from vtk.util.numpy_support import vtk_to_numpy
    r = vtk.vtkXMLUnstructuredGridReader() if path.endswith(".vtu") else vtk.vtkUnstructuredGridReader()
    # VTK's defaults, as a user's script has them: no ReadAllScalarsOn.
    r.SetFileName(path)
    r.Update()
    g = r.GetOutput()
    assert (vtk_to_numpy(g.GetCellTypesArray()) == 10).all()
    t = vtk_to_numpy(g.GetCells().GetConnectivityArray()).astype("int64").reshape(-1, 4)
    l = vtk_to_numpy(g.GetCellData().GetArray(key)).astype("int64")
print(len(t), int(t.sum()), int(l.sum()), int((l * t.sum(axis=1)).sum()))
)";

bool PythonImports(const std::string& module) {
  return RunProcess({kPython, "-c", absl::StrCat("import ", module)}).exit_code == 0;
}

std::array<long long, 4> Checksums(const io::MeshFile& file) {
  std::array<long long, 4> sums{static_cast<long long>(file.mesh.tets.size()), 0, 0, 0};
  for (size_t t = 0; t < file.mesh.tets.size(); ++t) {
    const Tet& k = file.mesh.tets[t];
    const long long index_sum = static_cast<long long>(k[0]) + k[1] + k[2] + k[3];
    sums[1] += index_sum;
    sums[2] += file.mesh.labels[t];
    sums[3] += file.mesh.labels[t] * index_sum;
  }
  return sums;
}

std::array<long long, 4> IndependentChecksums(const std::string& reader, const std::string& path,
                                              const std::string& key) {
  const ProcessResult run = RunProcess({kPython, "-c", kReaderScript, reader, path, key});
  EXPECT_EQ(run.exit_code, 0) << reader << " on " << path << ": " << run.out << run.err;
  std::array<long long, 4> sums{-1, -1, -1, -1};
  std::istringstream fields(run.out);
  fields >> sums[0] >> sums[1] >> sums[2] >> sums[3];
  return sums;
}

class CliOutput : public ::testing::Test {
 protected:
  void SetUp() override {
    volume_ = dir_.File("bump.nii");
    WriteVolume(volume_, BumpVolume({9, 9, 9}, {0.0, 0.0, 0.0}, {1.0, 1.0, 1.0}));
  }

  // A labelled input mesh (Gmsh keeps labels as physical groups), its pattern
  // depending on `seed`.
  std::string LabelledMesh(int seed) {
    io::MeshFile file;
    file.mesh = testing::FiveTetMesh({1, 1, 1}, {7, 7, 7}, {2, 2, 2});
    for (size_t t = 0; t < file.mesh.tets.size(); ++t) {
      file.mesh.labels.push_back(static_cast<int32_t>(1 + (t * (2 * seed + 1) + seed) % 4));
    }
    file.label_name = "region";
    const std::string path = dir_.File(absl::StrCat("labelled", seed, ".vtu"));
    EXPECT_TRUE(io::WriteMesh(path, file).ok());
    return path;
  }

  ProcessResult Refine(const std::string& mesh, const std::string& out,
                       const std::vector<std::string>& extra) {
    std::vector<std::string> args = {"refine", "--volume", volume_, "--mesh",    mesh, "--epsilon",
                                     "0.05",   "--output", out,     "--threads", "1"};
    args.insert(args.end(), extra.begin(), extra.end());
    return RunTetrefine(args);
  }

  ScratchDir dir_;
  std::string volume_;
};

// Waits (up to 60 s) until `cli` has started writing `out`, a FIFO nobody reads, and 200 ms more
// so that it is blocked in the open: the progress line "writing <out> ... " ends only when the
// write does. False if the line never came.
bool WaitUntilWriting(testing::ChildProcess& cli, const std::string& out) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
  while (!absl::StrContains(cli.Output(), "writing " + out)) {
    if (std::chrono::steady_clock::now() >= deadline) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(200));
  return true;
}

// Ctrl-C while the output is being written stops the run with 130 and nothing after it (the
// statistics file here); it went on to exit 0 (an outside review, 2026-11-28). SIGTERM and SIGHUP
// likewise, with 143 and 129: they killed the run at once and left a temporary file behind (an
// outside review, 2026-11-29). The output is a FIFO nobody reads, so the write is still blocked
// when the signal comes.
TEST_F(CliOutput, ASignalWhileWritingFinishesTheFileAndExitsWith128PlusIt) {
  for (const auto& [signal_number, said] : {std::pair{SIGINT, "interrupted"},
                                            {SIGTERM, "terminated (SIGTERM)"},
                                            {SIGHUP, "hung up (SIGHUP)"}}) {
    SCOPED_TRACE(said);
    const std::string mesh = LabelledMesh(0);
    const std::string out = dir_.File(absl::StrCat("fifo", signal_number, ".vtu"));
    ASSERT_EQ(mkfifo(out.c_str(), 0600), 0);
    const std::string stats = dir_.File(absl::StrCat("stats", signal_number, ".json"));
    std::unique_ptr<testing::ChildProcess> cli = testing::ChildProcess::Start(
        {TetrefinePath(), "refine", "--volume", volume_, "--mesh", mesh, "--epsilon", "0.05",
         "--output", out, "--stats-json", stats});
    ASSERT_NE(cli, nullptr);
    ASSERT_TRUE(WaitUntilWriting(*cli, out)) << cli->Output();
    cli->Signal(signal_number);
    const std::optional<int> code = cli->WaitExit(std::chrono::seconds(30));
    ASSERT_TRUE(code.has_value()) << cli->Output();
    EXPECT_EQ(*code, 128 + signal_number) << cli->Output();
    EXPECT_TRUE(absl::StrContains(cli->Output(), absl::StrCat(said, " while writing ", out)))
        << cli->Output();
    EXPECT_FALSE(FileExists(stats));
  }
}

// `nohup tetrefine refine ... &` must outlive its terminal: a SIGHUP the run was started with
// ignored stays ignored. The refine command's own handler caught it anyway until a read-through
// (2026-11-29): the closed terminal ended the run with 129. The output is a FIFO, so the run is
// still writing when the SIGHUP comes; a reader then drains it, and the run finishes with 0.
TEST_F(CliOutput, ASignalIgnoredUnderNohupDoesNotStopTheRun) {
  const std::string mesh = LabelledMesh(0);
  const std::string out = dir_.File("nohup.vtu");
  ASSERT_EQ(mkfifo(out.c_str(), 0600), 0);
  std::unique_ptr<testing::ChildProcess> cli =
      testing::ChildProcess::Start({"/usr/bin/nohup", TetrefinePath(), "refine", "--volume",
                                    volume_, "--mesh", mesh, "--epsilon", "0.05", "--output", out});
  ASSERT_NE(cli, nullptr);
  ASSERT_TRUE(WaitUntilWriting(*cli, out)) << cli->Output();
  cli->Signal(SIGHUP);
  // Caught, the signal ends the blocked open and the run (129). Only a run still waiting there
  // may be given a reader: opening the FIFO with no writer left would wait for ever.
  const std::optional<int> early = cli->WaitExit(std::chrono::milliseconds(500));
  ASSERT_FALSE(early.has_value()) << "exit " << *early << "\n" << cli->Output();
  const std::string written = ReadBytes(out);  // opens the FIFO: the write goes on
  const std::optional<int> code = cli->WaitExit(std::chrono::seconds(30));
  ASSERT_TRUE(code.has_value()) << cli->Output();
  EXPECT_EQ(*code, 0) << cli->Output();
  EXPECT_TRUE(absl::StrContains(written, "</VTKFile>"));
}

// The bits of `signal_number` in a /proc/<pid>/status signal mask line ("SigCgt", "SigIgn").
bool InSignalMask(pid_t pid, const std::string& field, int signal_number) {
  std::ifstream status(absl::StrCat("/proc/", pid, "/status"));
  std::string line;
  while (std::getline(status, line)) {
    if (absl::StartsWith(line, field + ":")) {
      const uint64_t mask = std::stoull(line.substr(field.size() + 1), nullptr, 16);
      return ((mask >> (signal_number - 1)) & 1) != 0;
    }
  }
  return false;
}

// Every command catches SIGINT, SIGTERM and SIGHUP to remove the temporary file of a write in
// progress (client/io/temporary_files.h, tested there), unless it was started ignoring one; the
// process still ends by the signal. `info` on a FIFO with no writer waits in its open.
TEST_F(CliOutput, EveryCommandCatchesTheEndingSignalsItDoesNotIgnore) {
  for (const bool nohup : {false, true}) {
    SCOPED_TRACE(nohup ? "under nohup" : "plain");
    const std::string fifo = dir_.File(absl::StrCat("blocked", nohup, ".vtu"));
    ASSERT_EQ(mkfifo(fifo.c_str(), 0600), 0);
    std::vector<std::string> argv = {TetrefinePath(), "info", fifo};
    if (nohup) argv.insert(argv.begin(), "/usr/bin/nohup");
    std::unique_ptr<testing::ChildProcess> cli = testing::ChildProcess::Start(argv);
    ASSERT_NE(cli, nullptr);
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(30);
    while (!InSignalMask(cli->pid(), "SigCgt", SIGTERM) &&
           std::chrono::steady_clock::now() < deadline) {
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    EXPECT_TRUE(InSignalMask(cli->pid(), "SigCgt", SIGTERM));
    EXPECT_TRUE(InSignalMask(cli->pid(), "SigCgt", SIGINT));
    EXPECT_EQ(InSignalMask(cli->pid(), "SigCgt", SIGHUP), !nohup);
    EXPECT_EQ(InSignalMask(cli->pid(), "SigIgn", SIGHUP), nohup);
    cli->Signal(SIGTERM);
    const std::optional<int> code = cli->WaitExit(std::chrono::seconds(30));
    ASSERT_TRUE(code.has_value()) << cli->Output();
    EXPECT_EQ(*code, 128 + SIGTERM) << cli->Output();
  }
}

// Every encoding, over several label patterns: our reader sees the same tets and labels as in
// the default output; the file shows the encoding asked for. Each encoding is run on one of the
// patterns, in turn (every pattern meets a third of the encodings): the label patterns vary the
// arrays' contents, the encodings how they are laid out, and the two do not interact. All three
// for every encoding (until 2026-11-24) was 48 CLI runs, 41 s under the sanitizers.
TEST_F(CliOutput, EveryEncodingFlagReadsBackTheSameTetsAndLabels) {
  const std::vector<Variant> variants = Variants();
  constexpr int kPatterns = 3;
  for (int seed = 1; seed <= kPatterns; ++seed) {
    const std::string in = LabelledMesh(seed);
    const std::string reference_path = dir_.File(absl::StrCat("reference", seed, ".vtu"));
    const ProcessResult reference_run = Refine(in, reference_path, {"--quiet"});
    ASSERT_EQ(reference_run.exit_code, 0) << reference_run.err;
    absl::StatusOr<io::MeshFile> reference = io::ReadMesh(reference_path);
    ASSERT_TRUE(reference.ok()) << reference.status();
    ASSERT_EQ(reference->mesh.labels.size(), reference->mesh.tets.size());
    ASSERT_GT(reference->mesh.tets.size(), 40u) << "the input should have been refined";
    for (size_t i = static_cast<size_t>(seed - 1); i < variants.size(); i += kPatterns) {
      const Variant& v = variants[i];
      SCOPED_TRACE(absl::StrCat("seed ", seed, ": ", Describe(v)));
      const std::string out = dir_.File(absl::StrCat("out", seed, "_", i, v.extension));
      std::vector<std::string> extra = v.flags;
      extra.push_back("--quiet");
      const ProcessResult run = Refine(in, out, extra);
      ASSERT_EQ(run.exit_code, 0) << run.err;
      EXPECT_TRUE(absl::StrContains(ReadBytes(out), v.marker)) << "no " << v.marker;
      absl::StatusOr<io::MeshFile> got = io::ReadMesh(out);
      ASSERT_TRUE(got.ok()) << got.status();
      EXPECT_EQ(got->mesh.points, reference->mesh.points);
      EXPECT_EQ(TetLabelPairs(*got), TetLabelPairs(*reference));
      if (v.extension != ".msh") {
        EXPECT_EQ(got->mesh.tets, reference->mesh.tets);
        EXPECT_EQ(got->mesh.labels, reference->mesh.labels);
        EXPECT_EQ(got->tet_quality, reference->tet_quality);
      }
    }
  }
}

// An LPS-tagged input refined into a format without a frame tag keeps its LPS numbers there
// (io::FormatMesh), and refine says the tag is lost; into .vtu the tag is kept, and no warning.
TEST_F(CliOutput, AnLpsInputWarnsWhereTheTagCannotBeWritten) {
  io::MeshFile lps;
  lps.mesh = testing::FiveTetMesh({1, 1, 1}, {7, 7, 7}, {2, 2, 2});
  lps.frame = io::MeshFrame::kLps;  // written with SPACE=LPS: the file stores -x, -y
  const std::string in = dir_.File("lps_in.vtu");
  ASSERT_TRUE(io::WriteMesh(in, lps).ok());
  for (const char* extension : {".msh", ".mesh", ".vtu"}) {
    SCOPED_TRACE(extension);
    const std::string out = dir_.File(absl::StrCat("lps_out", extension));
    const ProcessResult run = Refine(in, out, {"--quiet"});
    ASSERT_EQ(run.exit_code, 0) << run.err;
    const bool lost = std::string(extension) != ".vtu";
    EXPECT_EQ(absl::StrContains(run.err, out + ": written in the input's LPS coordinates, but "
                                               "this format has no place for the SPACE=LPS tag"),
              lost)
        << run.err;
    absl::StatusOr<io::MeshFile> got = io::ReadMesh(out);
    ASSERT_TRUE(got.ok()) << got.status();
    // The input's vertices come first: read back untagged, they are the LPS numbers.
    for (size_t i = 0; i < lps.mesh.points.size(); ++i) {
      const Vec3& p = lps.mesh.points[i];
      const Vec3 want = lost ? Vec3{-p[0], -p[1], p[2]} : p;
      EXPECT_EQ(got->mesh.points[i], want) << i;
    }
  }
}

// Negative labels reach a .msh as negative physical groups, which Gmsh reads as reversed
// orientation: refine says so (a Gmsh MSH 2.2 save merged -7 into 7, inside out); no warning
// for .vtu, or for a .msh of non-negative labels.
TEST_F(CliOutput, NegativeLabelsIntoMshWarnAboutGmsh) {
  io::MeshFile file;
  file.mesh = testing::FiveTetMesh({1, 1, 1}, {7, 7, 7}, {2, 2, 2});
  for (size_t t = 0; t < file.mesh.tets.size(); ++t) {
    file.mesh.labels.push_back(t % 3 == 0 ? -7 : (t % 3 == 1 ? 7 : -2));
  }
  file.label_name = "region";
  const std::string in = dir_.File("negative.vtu");
  ASSERT_TRUE(io::WriteMesh(in, file).ok());
  const ProcessResult to_msh = Refine(in, dir_.File("negative.msh"), {"--quiet"});
  ASSERT_EQ(to_msh.exit_code, 0) << to_msh.err;
  EXPECT_TRUE(absl::StrContains(to_msh.err, dir_.File("negative.msh") +
                                                ": negative labels (-7, -2) are written as "
                                                "negative physical groups"))
      << to_msh.err;
  absl::StatusOr<io::MeshFile> got = io::ReadMesh(dir_.File("negative.msh"));
  ASSERT_TRUE(got.ok()) << got.status();
  EXPECT_EQ(std::set<int32_t>(got->mesh.labels.begin(), got->mesh.labels.end()),
            (std::set<int32_t>{-7, -2, 7}));
  const ProcessResult to_vtu = Refine(in, dir_.File("negative_out.vtu"), {"--quiet"});
  ASSERT_EQ(to_vtu.exit_code, 0) << to_vtu.err;
  EXPECT_EQ(to_vtu.err, "");
  for (int32_t& label : file.mesh.labels) label = std::abs(label);
  ASSERT_TRUE(io::WriteMesh(in, file).ok());
  const ProcessResult positive = Refine(in, dir_.File("positive.msh"), {"--quiet"});
  ASSERT_EQ(positive.exit_code, 0) << positive.err;
  EXPECT_EQ(positive.err, "");
}

// Gmsh region names go through refine to a .msh output; other outputs say they drop them.
TEST_F(CliOutput, GmshRegionNamesReachAMshOutput) {
  io::MeshFile named;
  named.mesh = testing::FiveTetMesh({1, 1, 1}, {7, 7, 7}, {2, 2, 2});
  for (size_t t = 0; t < named.mesh.tets.size(); ++t) {
    named.mesh.labels.push_back(t % 2 == 0 ? 3 : 4);
  }
  named.label_name = "gmsh:physical";
  named.region_names = {{3, "grey matter"}, {4, "white matter"}};
  const std::string in = dir_.File("named_in.msh");
  ASSERT_TRUE(io::WriteMesh(in, named).ok());
  const ProcessResult to_msh = Refine(in, dir_.File("named_out.msh"), {"--quiet"});
  ASSERT_EQ(to_msh.exit_code, 0) << to_msh.err;
  EXPECT_EQ(to_msh.err, "");
  absl::StatusOr<io::MeshFile> got = io::ReadMesh(dir_.File("named_out.msh"));
  ASSERT_TRUE(got.ok()) << got.status();
  EXPECT_EQ(got->region_names, named.region_names);
  const ProcessResult to_vtu = Refine(in, dir_.File("named_out.vtu"), {"--quiet"});
  ASSERT_EQ(to_vtu.exit_code, 0) << to_vtu.err;
  EXPECT_TRUE(absl::StrContains(
      to_vtu.err, "the region names (3 \"grey matter\", 4 \"white matter\") are not written"))
      << to_vtu.err;
}

// The same files through meshio and VTK 9, the readers ParaView, Slicer and FEniCS users have.
TEST_F(CliOutput, IndependentReadersSeeTheSameTetsAndLabels) {
  const bool meshio = PythonImports("meshio");
  const bool vtk = PythonImports("vtk");
  if (!meshio && !vtk) GTEST_SKIP() << kPython << " has neither meshio nor vtk";
  const std::string in = LabelledMesh(1);
  const std::vector<Variant> variants = Variants();
  for (size_t i = 0; i < variants.size(); ++i) {
    const Variant& v = variants[i];
    SCOPED_TRACE(Describe(v));
    const std::string out = dir_.File(absl::StrCat("out", i, v.extension));
    std::vector<std::string> extra = v.flags;
    extra.push_back("--quiet");
    const ProcessResult run = Refine(in, out, extra);
    ASSERT_EQ(run.exit_code, 0) << run.err;
    absl::StatusOr<io::MeshFile> ours = io::ReadMesh(out);
    ASSERT_TRUE(ours.ok()) << ours.status();
    const std::array<long long, 4> want = Checksums(*ours);
    const std::string key = v.extension == ".msh" ? "gmsh:physical" : "region";
    const bool lz4 = absl::StrContains(Describe(v), "lz4");
    // meshio's VTU reader knows zlib and lzma only.
    if (meshio && !lz4) {
      EXPECT_EQ(IndependentChecksums("meshio", out, key), want) << "meshio";
    }
    // VTK has no Gmsh reader.
    if (vtk && v.extension != ".msh") {
      EXPECT_EQ(IndependentChecksums("vtk", out, key), want) << "vtk";
    }
  }
}

TEST_F(CliOutput, MeshCommandTakesTheSameFlags) {
  const std::string ascii = dir_.File("grid.vtk");
  const ProcessResult run =
      RunTetrefine({"mesh", "--volume", volume_, "--block", "2", "--output", ascii, "--ascii"});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_TRUE(absl::StrContains(ReadBytes(ascii), "\nASCII\n"));
  const std::string lz4 = dir_.File("grid.vtu");
  const ProcessResult run_lz4 = RunTetrefine(
      {"mesh", "--volume", volume_, "--block", "2", "--output", lz4, "--vtu-compression", "lz4"});
  ASSERT_EQ(run_lz4.exit_code, 0) << run_lz4.err;
  EXPECT_TRUE(absl::StrContains(ReadBytes(lz4), "vtkLZ4DataCompressor"));
  absl::StatusOr<io::MeshFile> a = io::ReadMesh(ascii);
  absl::StatusOr<io::MeshFile> b = io::ReadMesh(lz4);
  ASSERT_TRUE(a.ok()) << a.status();
  ASSERT_TRUE(b.ok()) << b.status();
  EXPECT_EQ(a->mesh.tets, b->mesh.tets);
  EXPECT_EQ(a->mesh.points, b->mesh.points);
}

TEST_F(CliOutput, BadEncodingValuesNameTheFlag) {
  const std::string in = LabelledMesh(1);
  struct Bad {
    std::vector<std::string> flags;
    std::string named;
  };
  const std::vector<Bad> bad = {
      {{"--vtu-compression", "gzip"}, "--vtu-compression"},
      {{"--vtu-compression", ""}, "--vtu-compression"},
      {{"--vtu-encoding", "raw"}, "--vtu-encoding"},
      {{"--binary", "--ascii"}, "--binary, --ascii"},
  };
  for (const Bad& b : bad) {
    for (const std::string command : {"refine", "mesh"}) {
      SCOPED_TRACE(absl::StrCat(command, " ", b.flags[0]));
      const std::string out = dir_.File("never.vtu");
      std::vector<std::string> args =
          command == "refine"
              ? std::vector<std::string>{"refine",    "--volume", volume_,    "--mesh", in,
                                         "--epsilon", "0.05",     "--output", out}
              : std::vector<std::string>{"mesh", "--volume", volume_, "--output", out};
      args.insert(args.end(), b.flags.begin(), b.flags.end());
      const ProcessResult run = RunTetrefine(args);
      EXPECT_EQ(run.exit_code, 2) << run.err;
      EXPECT_TRUE(absl::StrContains(run.err, b.named)) << run.err;
      EXPECT_EQ(SplitLines(run.err).size(), 1u) << "one line: " << run.err;
      EXPECT_FALSE(FileExists(out));
    }
  }
}

// Each phase of a run says when it starts or ends, in the order the phases run; --quiet says
// nothing.
TEST_F(CliOutput, RefineReportsEveryPhaseInOrderUnlessQuiet) {
  const std::string in = LabelledMesh(1);
  const std::string out = dir_.File("phases.vtu");
  const std::string stats = dir_.File("phases.json");
  const ProcessResult run =
      Refine(in, out, {"--stats-json", stats, "--every-iteration", "--max-iterations", "2"});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const std::vector<std::string> phases = {
      absl::StrCat("tetrefine: reading volume ", volume_, " ... 9x9x9 float64, 5.83 kB, "),
      absl::StrCat("tetrefine: reading mesh ", in, " ... "),
      "tetrefine: refining ",
      "tetrefine: sending the input ...",
      "tetrefine: sent ",
      "tetrefine: iteration 1: ",
      absl::StrCat("tetrefine: writing ", dir_.File("phases.iter01.vtu"), " ... "),
      "tetrefine: iteration 2: ",
      absl::StrCat("tetrefine: writing ", dir_.File("phases.iter02.vtu"), " ... "),
      "tetrefine: service done after 2 iterations; the stop test and the lattice check (order "
      "8) took ",
      "tetrefine: receiving the refined mesh: ",
      "tetrefine: received the refined mesh: ",
      absl::StrCat("tetrefine: writing ", out, " ... "),
      absl::StrCat("tetrefine: writing ", stats, " ... "),
  };
  // Lines saying the service is still working come after silences of 2 s, so only on a slow
  // machine; they are not phases.
  std::vector<std::string> lines;
  for (const std::string& line : SplitLines(run.err)) {
    if (!absl::StrContains(line, "the service is still working")) lines.push_back(line);
  }
  ASSERT_EQ(lines.size(), phases.size()) << run.err;
  for (size_t i = 0; i < lines.size(); ++i) {
    EXPECT_TRUE(absl::StartsWith(lines[i], phases[i])) << lines[i] << "\nwanted " << phases[i];
    // Phases with a clock end with their time.
    if (absl::StrContains(phases[i], " ... ")) {
      EXPECT_TRUE(absl::EndsWith(lines[i], " s")) << lines[i];
    }
  }
  EXPECT_TRUE(absl::StrContains(lines[1], " vertices, 40 tets, ")) << lines[1];
  absl::StatusOr<io::MeshFile> got = io::ReadMesh(out);
  ASSERT_TRUE(got.ok()) << got.status();
  EXPECT_TRUE(absl::StrContains(
      run.err, absl::StrCat("writing ", out, " ... ", got->mesh.tets.size(), " tets, ")))
      << run.err;

  const ProcessResult quiet = Refine(in, dir_.File("quiet.vtu"),
                                     {"--stats-json", dir_.File("quiet.json"), "--every-iteration",
                                      "--max-iterations", "2", "--quiet"});
  ASSERT_EQ(quiet.exit_code, 0) << quiet.err;
  EXPECT_EQ(quiet.err, "");
  EXPECT_TRUE(absl::StrContains(quiet.out, "Stopped after 2 iteration")) << quiet.out;
}

// A phase that fails ends its line, so the error starts a line of its own.
TEST_F(CliOutput, FailedPhaseEndsItsLineBeforeTheError) {
  const std::string broken = dir_.File("broken.vtu");
  io::iotest::WriteBytes(broken, "<VTKFile");
  const ProcessResult run = Refine(broken, dir_.File("never.vtu"), {});
  EXPECT_EQ(run.exit_code, 2) << run.err;
  const std::vector<std::string> lines = SplitLines(run.err);
  ASSERT_EQ(lines.size(), 3u) << run.err;
  EXPECT_TRUE(absl::EndsWith(lines[1], " ... failed")) << lines[1];
  EXPECT_TRUE(absl::StrContains(lines[2], broken)) << lines[2];
}

// Counts and sizes keep three significant digits: the number they show is within 0.5% of the
// value, for values over many magnitudes.
TEST(CliProgressFormat, CountsAndBytesStayWithinHalfAPercent) {
  std::mt19937_64 random(7);
  for (int i = 0; i < 2000; ++i) {
    const int64_t n = static_cast<int64_t>(random() >> (1 + random() % 63));
    for (const bool bytes : {false, true}) {
      const std::string text = bytes ? FormatBytes(n) : FormatCount(n);
      SCOPED_TRACE(absl::StrCat(n, " -> ", text));
      std::istringstream fields(text);
      double shown = 0.0;
      std::string suffix;
      fields >> shown >> suffix;
      ASSERT_FALSE(fields.fail() && !fields.eof());
      double scale = 1.0;
      if (suffix == "k" || suffix == "kB") scale = 1e3;
      if (suffix == "M" || suffix == "MB") scale = 1e6;
      if (suffix == "G" || suffix == "GB") scale = 1e9;
      if (bytes) {
        EXPECT_TRUE(absl::EndsWith(suffix, "B"));
      } else if (n < 10000) {
        EXPECT_EQ(text, std::to_string(n));
      }
      EXPECT_NEAR(shown * scale, static_cast<double>(n), 0.005 * static_cast<double>(n) + 0.5);
    }
  }
  EXPECT_EQ(FormatCount(1600000), "1.60 M");
  EXPECT_EQ(FormatBytes(31400000), "31.4 MB");
  EXPECT_EQ(FormatSeconds(0.424), "0.42 s");
}

}  // namespace
}  // namespace tetrefine::clitest
