// tetrefine_reproduce: runs the paper's experiments (section 5) on the real volumes in the shared
// data directory and on generated phantoms with every tetrefine scheme, against DOLFINx's Plaza
// refinement (when python3-dolfinx is installed) and a uniform 1:8 baseline, and writes
// report.md, results.json and plots/*.svg into --out_dir.
// Run: build/tools/reproduce/tetrefine_reproduce --out_dir=docs/results
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <string>
#include <thread>
#include <vector>

#include "absl/flags/flag.h"
#include "absl/flags/parse.h"
#include "absl/flags/usage.h"
#include "absl/flags/usage_config.h"
#include "absl/strings/match.h"
#include "absl/strings/str_cat.h"
#include "core/refine.h"
#include "tools/reproduce/case_runner.h"
#include "tools/reproduce/cases.h"
#include "tools/reproduce/plaza_peer.h"
#include "tools/reproduce/report_markdown.h"
#include "tools/reproduce/results_json.h"
#include "tools/reproduce/schemes.h"
#include "tools/reproduce/svg_plot.h"

ABSL_FLAG(std::string, out_dir, TETREFINE_SOURCE_DIR "/docs/results",
          "where report.md, results.json and plots/ go");
ABSL_FLAG(std::string, data_dir, TETREFINE_SHARED_DATA_DIR,
          "directory of the real volumes and unit_cube_1782tets.mesh");
ABSL_FLAG(bool, quick, false, "two tiny generated cases, small caps (for the smoke test)");
ABSL_FLAG(int, max_iterations, 32,
          "iteration cap (tetrefine) and round cap (Plaza) of the runs 'to convergence'");
ABSL_FLAG(int64_t, max_tets, 2'000'000,
          "RefineOptions::max_tets of every run: keeps the cases that do not converge bounded");
ABSL_FLAG(int64_t, uniform_cap_tets, 3'000'000, "largest uniform level built (tets)");
ABSL_FLAG(int64_t, study_max_tets, 100'000, "tets examined per mesh in the section 5.1 study");
ABSL_FLAG(bool, peers, false,
          "run Plaza and fail if python3-dolfinx is missing (default: run it when it imports)");
ABSL_FLAG(bool, skip_peers, false, "do not run Plaza");
ABSL_FLAG(std::string, python, "/usr/bin/python3",
          "the Python interpreter python3-dolfinx is installed for");
ABSL_FLAG(std::string, plaza_script, TETREFINE_SOURCE_DIR "/bench/peers/plaza_refine.py",
          "the Plaza driver script");
ABSL_FLAG(std::string, peer_dir, "",
          "keep Plaza's inputs and results here, one directory per case (default: a temporary "
          "directory, removed at the end)");

namespace tetrefine::reproduce {
namespace {

using Clock = std::chrono::steady_clock;

std::string UtcNow() {
  const std::time_t t = std::time(nullptr);
  std::tm tm{};
  gmtime_r(&t, &tm);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%SZ", &tm);
  return buf;
}

bool WriteFile(const std::filesystem::path& path, const std::string& text) {
  std::ofstream f(path, std::ios::binary | std::ios::trunc);
  f << text;
  f.close();
  if (!f) {
    std::fprintf(stderr, "cannot write %s\n", path.c_str());
    return false;
  }
  return true;
}

int Main(int argc, char** argv) {
  std::vector<std::string> args(argv, argv + argc);
  absl::SetProgramUsageMessage(
      "Runs the paper's experiments with every tetrefine scheme, Plaza (DOLFINx) and uniform\n"
      "1:8, and writes report.md, results.json and plots/ into --out_dir.\n"
      "Usage: tetrefine_reproduce [--flag=value ...]; every flag is listed below.");
  // --help lists this file's flags (Abseil's default looks for files named after the program).
  absl::FlagsUsageConfig usage;
  usage.contains_help_flags = [](absl::string_view file) {
    return absl::EndsWith(file, "tools/reproduce/main.cc");
  };
  usage.contains_helpshort_flags = usage.contains_help_flags;
  absl::SetFlagsUsageConfig(usage);
  absl::ParseCommandLine(argc, argv);
  const auto start = Clock::now();
  const bool quick = absl::GetFlag(FLAGS_quick);
  const std::filesystem::path out_dir = absl::GetFlag(FLAGS_out_dir);

  ReportData data;
  data.generated_at = UtcNow();
  data.command = std::filesystem::path(args[0]).filename().string();
  for (size_t i = 1; i < args.size(); ++i) absl::StrAppend(&data.command, " ", args[i]);
  data.quick = quick;
  data.hardware_threads = static_cast<int>(std::thread::hardware_concurrency());

  RunOptions run;
  run.max_iterations = absl::GetFlag(FLAGS_max_iterations);
  run.uniform_cap_tets = quick ? 200'000 : absl::GetFlag(FLAGS_uniform_cap_tets);
  run.max_tets = absl::GetFlag(FLAGS_max_tets);
  if (run.max_iterations < 1 || run.uniform_cap_tets < 1 || run.max_tets < 1) {
    std::fprintf(stderr, "--max_iterations, --max_tets and --uniform_cap_tets must be positive\n");
    return 2;
  }
  if (absl::GetFlag(FLAGS_peers) && absl::GetFlag(FLAGS_skip_peers)) {
    std::fprintf(stderr, "--peers and --skip_peers contradict each other\n");
    return 2;
  }
  PlazaPeer plaza{.python = absl::GetFlag(FLAGS_python),
                  .script = absl::GetFlag(FLAGS_plaza_script),
                  .max_rounds = run.max_iterations,
                  .max_tets = run.max_tets};
  std::filesystem::path temporary_peer_dir;
  if (absl::GetFlag(FLAGS_skip_peers)) {
    run.plaza_not_run = "--skip_peers";
  } else if (const absl::Status s = CheckPlaza(plaza); !s.ok()) {
    if (absl::GetFlag(FLAGS_peers)) {
      std::fprintf(stderr, "--peers: cannot run Plaza: %s (bash bench/peers/install-peers.sh)\n",
                   std::string(s.message()).c_str());
      return 2;
    }
    run.plaza_not_run = std::string(s.message());
    std::fprintf(stderr, "note: Plaza not run: %s\n", run.plaza_not_run.c_str());
  } else {
    run.plaza = &plaza;
    run.peer_dir = absl::GetFlag(FLAGS_peer_dir);
    if (run.peer_dir.empty()) {
      temporary_peer_dir = std::filesystem::temp_directory_path() /
                           absl::StrCat("tetrefine_reproduce_peers_", getpid());
      run.peer_dir = temporary_peer_dir;
    }
  }
  data.plaza_status = run.plaza != nullptr ? "run" : absl::StrCat("not run: ", run.plaza_not_run);
  for (const Scheme& scheme : kSchemes) data.schemes.emplace_back(scheme.name);
  data.epsilons = run.epsilons;
  data.max_iterations = run.max_iterations;
  data.max_tets = run.max_tets;
  data.uniform_cap_tets = run.uniform_cap_tets;
  data.study_max_tets = quick ? 20'000 : absl::GetFlag(FLAGS_study_max_tets);
  data.study_thresholds = {0.001, 0.05};

  std::fprintf(stderr, "building inputs\n");
  // Canonical, so that notes name /work/shared/data rather than /work/main/../shared/data.
  std::error_code ignored;
  std::filesystem::path data_dir =
      std::filesystem::weakly_canonical(absl::GetFlag(FLAGS_data_dir), ignored);
  if (data_dir.empty()) data_dir = absl::GetFlag(FLAGS_data_dir);
  Inputs inputs = BuildInputs({.data_dir = data_dir.string(), .quick = quick});
  data.notes = inputs.notes;
  for (const std::string& n : inputs.notes) std::fprintf(stderr, "note: %s\n", n.c_str());
  if (inputs.cases.empty()) {
    std::fprintf(stderr, "no cases to run\n");
    return 1;
  }
  {
    // Untimed: the first Refine of a process also starts the thread pool and builds the
    // subdivision table, which is no case's cost.
    RefineOptions warm_up;
    warm_up.max_iterations = 1;
    warm_up.lattice_n = 0;
    (void)Refine(*inputs.cases.front().volume, inputs.cases.front().mesh, warm_up);
  }
  for (const CaseInput& c : inputs.cases) {
    std::fprintf(stderr, "case %s (%zu tets)\n", c.name.c_str(), c.mesh.tets.size());
    data.cases.push_back(RunCase(c, run));
  }
  std::fprintf(stderr, "section 5.1 study\n");
  for (StudyInput& s : inputs.study) {
    const auto [lo, hi] = s.volume->ValueRange();
    data.study.push_back(
        {s.label, s.kind,
         StudyMaxLocation(*s.volume, std::move(s.mesh), hi > lo ? hi - lo : 1.0,
                          data.study_thresholds, data.study_max_tets, /*seed=*/20261122)});
  }
  data.total_seconds = std::chrono::duration<double>(Clock::now() - start).count();
  if (!temporary_peer_dir.empty()) std::filesystem::remove_all(temporary_peer_dir, ignored);
  // The version the script reported, once any Plaza run succeeded.
  for (const CaseRecord& c : data.cases) {
    for (const MethodRow& m : c.methods) {
      if (m.has_self_report && data.plaza_status == "run") {
        data.plaza_status = absl::StrCat("run with ", m.self_report.version);
      }
    }
  }

  std::error_code ec;
  std::filesystem::create_directories(out_dir / "plots", ec);
  if (ec) {
    std::fprintf(stderr, "cannot create %s: %s\n", (out_dir / "plots").c_str(),
                 ec.message().c_str());
    return 1;
  }
  bool ok = WriteFile(out_dir / "report.md", ReportMarkdown(data)) &&
            WriteFile(out_dir / "results.json", ResultsJson(data));
  for (const CaseRecord& c : data.cases) {
    ok = ok && WriteFile(out_dir / "plots" / (c.name + ".svg"), CasePlotSvg(c));
  }
  std::fprintf(stderr, "%s %s in %.1f s\n", ok ? "wrote" : "FAILED writing",
               (out_dir / "report.md").c_str(), data.total_seconds);
  return ok ? 0 : 1;
}

}  // namespace
}  // namespace tetrefine::reproduce

int main(int argc, char** argv) { return tetrefine::reproduce::Main(argc, argv); }
