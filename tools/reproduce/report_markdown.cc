#include "tools/reproduce/report_markdown.h"

#include <algorithm>
#include <array>
#include <map>
#include <vector>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/strings/str_join.h"
#include "core/configuration.h"
#include "core/lattice.h"
#include "tools/reproduce/paper_tables.h"
#include "tools/reproduce/schemes.h"

namespace tetrefine::reproduce {
namespace {

std::string Err(double e) { return absl::StrFormat("%.4f", e); }
std::string Pct(double share) { return absl::StrFormat("%.1f%%", 100.0 * share); }
std::string Pct(int64_t part, int64_t whole) {
  return whole > 0 ? Pct(static_cast<double>(part) / static_cast<double>(whole)) : "-";
}
std::string MiB(int64_t bytes) {
  return bytes < 0 ? "n/a" : absl::StrFormat("%.1f", static_cast<double>(bytes) / (1 << 20));
}

std::string Match(const BaselineMatch& m, int64_t ours, const CaseRecord& c) {
  if (!m.reached) {
    const int64_t last = c.uniform.empty() ? 0 : c.uniform.back().tets;
    return absl::StrFormat("> %d (not reached)", last);
  }
  return absl::StrFormat(
      "%d (L%d, %.2fx)", m.tets, m.level,
      static_cast<double>(m.tets) / static_cast<double>(std::max<int64_t>(1, ours)));
}

std::string Sorted3(std::vector<double> v) {
  if (v.empty()) return "-";
  std::sort(v.begin(), v.end());
  return absl::StrFormat("%.3g / %.3g / %.3g", v.front(), v[v.size() / 2], v.back());
}

// The method names in row order (the first case that has rows decides).
std::vector<std::string> MethodNames(const ReportData& d) {
  std::vector<std::string> names;
  for (const CaseRecord& c : d.cases) {
    for (const MethodRow& m : c.methods) {
      if (std::find(names.begin(), names.end(), m.method) == names.end()) {
        names.push_back(m.method);
      }
    }
  }
  return names;
}

std::vector<const MethodRow*> RowsOf(const ReportData& d, const std::string& method) {
  std::vector<const MethodRow*> rows;
  for (const CaseRecord& c : d.cases) {
    for (const MethodRow& m : c.methods) {
      if (m.method == method) rows.push_back(&m);
    }
  }
  return rows;
}

void Method(const ReportData& d, std::string& s) {
  absl::StrAppend(&s, "## How these numbers were made\n\n",
                  "- **Methods**, each run at ε = ", absl::StrJoin(d.epsilons, " and "),
                  " on every case and scored the same way (below):\n");
  for (const Scheme& scheme : kSchemes) {
    absl::StrAppend(&s, "  - **tetrefine ", scheme.name, "**: ", scheme.description, ".\n");
  }
  absl::StrAppend(
      &s, "  - **Plaza (DOLFINx)**: `bench/peers/plaza_refine.py` under Debian's python3-dolfinx (",
      d.plaza_status,
      "): each round samples the volume at every vertex, marks the edges whose midpoint error "
      "(eq. 3, computed as core computes it) exceeds ε and calls `dolfinx.mesh.refine(mesh, "
      "edges, redistribute=False)`, which is Plaza and Carey's skeleton refinement: it also "
      "splits the longest edge of every face that has a split edge, to a fixpoint, so tets are "
      "bisected along their longest edges. Rounds stop when no edge is marked (`converged`), "
      "after the round cap (`max_rounds`) or before a round that would exceed `max_tets` "
      "(`tet_budget`). The tool passes it the case as files (volume samples, grid, mesh; "
      "`--peer_dir` keeps them) and reads the refined mesh back; install it with "
      "`bash bench/peers/install-peers.sh`.\n",
      "  - **uniform 1:8**: regular 1:8 refinement of every tet (all six edges split, the "
      "octahedron cut by its shortest diagonal: core's subdivision table entry for pattern 63; "
      "`tools/reproduce/uniform_refine.h`), new vertices valued from the volume, level after "
      "level until the lattice max and mean error are at most every other result's and the "
      "lattice max at most the smallest ε, or until the next level would exceed ",
      d.uniform_cap_tets,
      " tets. Its row gives the first level whose lattice max error is at most ε "
      "(`lattice_reached`), else the last level built (`tet_cap`); \"uniform tets at equal "
      "lattice max\" in the other rows is the first level whose lattice max error is at most "
      "that row's, and the factor its tets over the row's.\n",
      "- **Caps**: tetrefine's `max_iterations` and Plaza's rounds ", d.max_iterations,
      "; `max_tets` ", d.max_tets,
      " for both (a run that would exceed it stops with `tet_budget`). The paper scheme also "
      "runs 4 iterations per ε for the paper's four-iteration tables. tetrefine runs with "
      "default options otherwise and `lattice_n = 0`.\n",
      "- **Scores**, the same code for every method's result: the edge-midpoint error over its "
      "unique edges (what a next round would mark), core `SampleLattice` (n = 8: the 165 "
      "barycentric points of the paper's section 5.1 per tet; every tet of meshes up to "
      "3,000,000 tets, a seeded sample beyond) and mean-ratio quality over every tet. The "
      "normalisation is the volume's value range. Plaza's script scores its result itself as "
      "well (in numpy); results.json keeps its figures beside core's.\n",
      "- **Tables 3-7** per case below come from `RefineResult::iterations` of each tetrefine "
      "scheme: tets by configuration (Tables 3/4), Schönhardt prisms given a Steiner point (SP), "
      "INT/FNT/NTwE and the maximum and mean edge-midpoint error at the start of each iteration "
      "(Tables 5/6), and mean-ratio quality before and after (Table 7).\n",
      "- **Real volumes** (`/work/shared/data`, read with `io::ReadVolume`): meshes are 5-tet "
      "blocks masked like the paper's liver: a block is kept when all 8 corner samples exceed "
      "Otsu's threshold of the volume (256 bins), blocks of the smallest size in {2, 3, 4, 5, 6, "
      "8} voxels giving at most 10,000 tets, so that the initial mesh is coarse like the paper's "
      "(1,000-11,000 tets). The unstructured cube mesh (`unit_cube_1782tets.mesh`) is scaled per "
      "axis onto each volume's box less 5% on every side.\n",
      "- **Phantoms** (generated, `tools/reproduce/phantoms.h`): the heart SPECT data of the "
      "paper is not available; a left-ventricle perfusion phantom (thick ellipsoidal shell open "
      "at the base, tilted, smooth regional pattern, cold inferior defect, a liver-like blob, "
      "PSF-like blur across the wall, no noise) is point-sampled on the paper's two heart grids "
      "(Table 2). Its mesh is one shell of 8 mm world cells (5 tets each) whose centres lie in "
      "the wall, used on both grids as the paper used one surface pair. The Marschner-Lobb signal "
      "is sampled on 41^3.\n",
      "- **Time and memory**: tetrefine: wall time of the `Refine` call alone (all ",
      d.hardware_threads,
      " hardware threads). Plaza: wall time of its rounds (sampling, marking, refining) in one "
      "Python process on one core, without interpreter start-up and the mesh's construction. "
      "Uniform: the levels' refinement up to the level shown. Peak memory (tetrefine only) is the "
      "resident high-water mark the call adds (VmHWM reset through /proc/self/clear_refs just "
      "before it, after returning free heap with malloc_trim), measured inside this "
      "long-running tool: heap the allocator kept from earlier cases can hide part of it, so "
      "read it as a lower bound (bench/peak_memory measures in a fresh process).\n\n");
}

std::string RowUniform(const MethodRow& m, const CaseRecord& c) {
  if (m.method == kUniformMethod) return "";
  return Match(m.uniform_at_max, m.tets, c);
}

void MethodsTable(const ReportData& d, std::string& s) {
  absl::StrAppend(
      &s, "## Methods side by side\n\n", "Per case and ε, every method to convergence (at most ",
      d.max_iterations,
      " iterations or rounds), scored the same way. Midpoint: the largest edge-midpoint error of "
      "the result; lattice: over the n = 8 lattice of every tet; quality: mean ratio.\n\n",
      "| case | ε | method | tets | rounds | midpoint max | lattice max / mean | quality min / "
      "mean | stop | time (s) | uniform tets at equal lattice max |\n",
      "|---|---|---|---|---|---|---|---|---|---|---|\n");
  for (const CaseRecord& c : d.cases) {
    for (const MethodRow& m : c.methods) {
      if (!m.not_run.empty()) {
        absl::StrAppendFormat(&s, "| [%s](#%s) | %g | %s | not run: %s | | | | | | | |\n", c.name,
                              c.name, m.epsilon, m.method, m.not_run);
        continue;
      }
      absl::StrAppendFormat(&s,
                            "| [%s](#%s) | %g | %s | %d | %d | %s | %s / %s | %.4f / %.4f | %s | "
                            "%.3f | %s |\n",
                            c.name, c.name, m.epsilon, m.method, m.tets, m.rounds,
                            Err(m.midpoint_max), Err(m.lattice.max_error),
                            Err(m.lattice.mean_error), m.quality.min, m.quality.mean, m.stop_reason,
                            m.seconds, RowUniform(m, c));
    }
  }
  s += "\n";
}

// One line on how uniform refinement compares at equal error over all runs to convergence.
std::string UniformLine(const ReportData& d, bool by_max) {
  int more = 0, fewer = 0, missed = 0;
  std::vector<double> factors;
  for (const CaseRecord& c : d.cases) {
    for (const RunRecord* r : RunsToConvergence(c, kPaperScheme.name)) {
      const BaselineMatch& m = by_max ? r->uniform_at_max : r->uniform_at_mean;
      if (r->final_tets == 0) continue;
      if (!m.reached) {
        ++missed;
        continue;
      }
      (m.tets > r->final_tets ? more : fewer) += 1;
      factors.push_back(static_cast<double>(m.tets) / static_cast<double>(r->final_tets));
    }
  }
  std::sort(factors.begin(), factors.end());
  const double median = factors.empty() ? 0.0 : factors[factors.size() / 2];
  return absl::StrFormat(
      "- At equal lattice %s error, uniform 1:8 refinement needed more tets than tetrefine's "
      "paper scheme in %d runs and fewer (or as many) in %d; in %d it did not get there within "
      "the cap. Median factor (uniform / tetrefine tets) where it did: %.2f.\n",
      by_max ? "max" : "mean", more, fewer, missed, median);
}

// How uniform 1:8 compares with one method's rows at equal lattice max error: the issue's
// question "does this method beat refining everywhere?", asked of every method, not only the paper
// scheme (UniformLine). Rows whose uniform match missed the cap count apart.
std::string UniformAgainst(const std::vector<const MethodRow*>& rows) {
  int more = 0, fewer = 0, missed = 0;
  std::vector<double> factors;
  for (const MethodRow* m : rows) {
    if (!m->not_run.empty() || m->tets == 0) continue;
    if (!m->uniform_at_max.reached) {
      ++missed;
      continue;
    }
    (m->uniform_at_max.tets > m->tets ? more : fewer) += 1;
    factors.push_back(static_cast<double>(m->uniform_at_max.tets) / static_cast<double>(m->tets));
  }
  if (more + fewer + missed == 0) return "";
  std::string out = absl::StrFormat(
      "; at its lattice max error uniform 1:8 needed more tets in %d runs, as many or fewer in %d, "
      "and did not get there within the cap in %d",
      more, fewer, missed);
  if (!factors.empty()) {
    absl::StrAppend(&out, " (uniform / its tets: ", Sorted3(factors), ")");
  }
  return out;
}

// One line per method: how its runs stopped, its tets against Plaza's where both reached ε at
// every midpoint, and its quality.
void MethodFindings(const ReportData& d, std::string& s) {
  const std::vector<const MethodRow*> plaza = RowsOf(d, kPlazaMethod);
  for (const std::string& name : MethodNames(d)) {
    const std::vector<const MethodRow*> rows = RowsOf(d, name);
    std::map<std::string, int> stops;
    int ran = 0;
    std::vector<double> qmin, qmean;
    for (const MethodRow* m : rows) {
      if (!m->not_run.empty()) continue;
      ++ran;
      ++stops[m->stop_reason];
      qmin.push_back(m->quality.min);
      qmean.push_back(m->quality.mean);
    }
    if (ran == 0) {
      absl::StrAppend(&s, "- **", name, "**: not run (",
                      rows.empty() ? "no cases" : rows.front()->not_run, ").\n");
      continue;
    }
    std::vector<std::string> parts;
    for (const auto& [reason, n] : stops) parts.push_back(absl::StrCat(n, " ", reason));
    absl::StrAppend(&s, "- **", name, "**: ", ran, " runs; stopped: ", absl::StrJoin(parts, ", "),
                    ". Quality min ", Sorted3(qmin), ", mean ", Sorted3(qmean),
                    " (least / median / largest over runs)");
    if (name != kPlazaMethod && name != kUniformMethod && rows.size() == plaza.size()) {
      // Rows line up: the same cases and epsilons in the same order.
      std::vector<double> ratio;
      int fewer = 0;
      for (size_t i = 0; i < rows.size(); ++i) {
        const MethodRow& a = *rows[i];
        const MethodRow& p = *plaza[i];
        if (!a.not_run.empty() || !p.not_run.empty()) continue;
        if (a.stop_reason != "converged" || p.stop_reason != "converged") continue;
        ratio.push_back(static_cast<double>(a.tets) / static_cast<double>(p.tets));
        if (a.tets <= p.tets) ++fewer;
      }
      if (!ratio.empty()) {
        absl::StrAppend(&s, "; where it and Plaza both reached ε at every midpoint (", ratio.size(),
                        " runs) its tets over Plaza's: ", Sorted3(ratio), ", at most Plaza's in ",
                        fewer);
      } else if (!plaza.empty() && plaza.front()->not_run.empty()) {
        s += "; no run where it and Plaza both reached ε at every midpoint";
      }
    }
    if (name != kUniformMethod) s += UniformAgainst(rows);
    s += ".\n";
  }
}

void Findings(const ReportData& d, std::string& s) {
  absl::StrAppend(&s, "## Findings (computed from the tables below)\n\n");
  MethodFindings(d, s);
  absl::StrAppend(&s, UniformLine(d, true), UniformLine(d, false));
  std::map<std::pair<std::string, double>, std::array<int64_t, 3>> pooled;  // counted, mid, near
  for (const StudyRecord& r : d.study) {
    for (const LocationCounts& c : r.study.counts) {
      auto& p = pooled[{r.kind, c.threshold}];
      p[0] += c.counted;
      p[1] += c.by_location[static_cast<int>(MaxLocation::kEdgeMidpoint)];
      p[2] += c.near_midpoint;
    }
  }
  for (const auto& [key, p] : pooled) {
    absl::StrAppend(
        &s, "- Section 5.1, ", key.first, " meshes, threshold ", absl::StrFormat("%g", key.second),
        ": the largest lattice error lies at an edge "
        "midpoint in ",
        Pct(p[1], p[0]), " of ", p[0], " tets, at or near one in ", Pct(p[2], p[0]),
        key.first == "voxel-aligned" ? " (paper: 93% at one).\n"
                                     : (key.second < 0.01 ? " (paper: 73% at or near one).\n"
                                                          : " (paper: 85% at or near one).\n"));
  }
  s += "\n";
}

constexpr const char* kLocationHeaders =
    "vertex | edge midpoint | other edge point | face | interior";

void Study(const ReportData& d, std::string& s) {
  absl::StrAppend(
      &s, "## Section 5.1: where the largest discrepancy lies\n\n",
      "For each tet (all tets, or a seeded random sample of ", d.study_max_tets,
      " without replacement on larger meshes), the point of largest error on the n = 8 lattice "
      "(165 points) as core `SampleTetLattice` reports it (`MaxLocation`; ties go to the first "
      "point in its scan order). A tet is counted at a threshold when that largest error exceeds "
      "it: tets that agree everywhere have no meaningful maximum. \"Near\" adds the lattice points "
      "one step from an edge midpoint (barycentric L1 distance 2/8), the paper's \"at the midpoint "
      "of some edge or in a point near to this one\". Voxel-aligned meshes are the volumes' "
      "5-tets-per-voxel meshes (masked like the blocks); coarse meshes are the cases' initial "
      "meshes. The paper reports 93% at an edge midpoint for voxel-aligned meshes, and for coarse "
      "meshes 73% (threshold 0.001) and 85% (threshold 0.05) at or near one.\n\n",
      "| mesh | kind | tets (sampled) | threshold | counted | ", kLocationHeaders,
      " | at or near a midpoint |\n|---|---|---|---|---|---|---|---|---|---|---|\n");
  // Pooled per kind and threshold.
  std::map<std::pair<std::string, double>, LocationCounts> pooled;
  for (const StudyRecord& r : d.study) {
    for (const LocationCounts& c : r.study.counts) {
      absl::StrAppendFormat(&s, "| %s | %s | %d (%d) | %g | %d |", r.mesh, r.kind, r.study.tets,
                            r.study.tets_sampled, c.threshold, c.counted);
      for (int64_t n : c.by_location) absl::StrAppend(&s, " ", Pct(n, c.counted), " |");
      absl::StrAppend(&s, " ", Pct(c.near_midpoint, c.counted), " |\n");
      LocationCounts& p = pooled[{r.kind, c.threshold}];
      p.threshold = c.threshold;
      p.counted += c.counted;
      p.near_midpoint += c.near_midpoint;
      for (int l = 0; l < kNumMaxLocations; ++l) p.by_location[l] += c.by_location[l];
    }
  }
  for (const auto& [key, c] : pooled) {
    absl::StrAppendFormat(&s, "| **all %s meshes** | %s | | %g | %d |", key.first, key.first,
                          c.threshold, c.counted);
    for (int64_t n : c.by_location) absl::StrAppend(&s, " **", Pct(n, c.counted), "** |");
    absl::StrAppend(&s, " **", Pct(c.near_midpoint, c.counted), "** |\n");
  }
  int64_t mismatches = 0;
  for (const StudyRecord& r : d.study) mismatches += r.study.class_mismatches;
  absl::StrAppend(
      &s, "\nThe tool's own scan for the argmax point agreed with core's location class on ",
      mismatches == 0 ? "every tet" : absl::StrCat("all but ", mismatches, " tets"), ".\n\n");
}

void PaperComparison(const ReportData& d, std::string& s) {
  std::map<std::pair<std::string, double>, const RunRecord*> ours;
  for (const CaseRecord& c : d.cases) {
    if (c.mesh_kind != "shell") continue;
    const std::string heart = c.name.substr(0, c.name.find('_'));
    for (const RunRecord& r : c.runs) {
      if (r.scheme != kPaperScheme.name) continue;
      // The paper reports four iterations: prefer the 4-iteration run (its quality is after 4).
      auto [it, inserted] = ours.try_emplace({heart, r.epsilon}, &r);
      if (!inserted && r.max_iterations == 4) it->second = &r;
    }
  }
  if (ours.empty()) return;
  absl::StrAppend(
      &s, "## The heart phantoms beside the paper's Tables 5-7\n\n",
      "The paper's heart1/heart2 are real SPECT studies meshed between reconstructed surfaces; "
      "ours are a phantom on the same grids with a staircase shell mesh, so only the shape of the "
      "numbers compares: how fast FNT levels off and the errors fall. Ours: the runs of at most "
      "4 iterations.\n\n",
      "| data | ε | iter | paper INT → FNT | paper NTwE | paper max / mean | ours INT → FNT | ours "
      "NTwE | ours max / mean |\n|---|---|---|---|---|---|---|---|---|\n");
  for (const PaperCase& p : kPaperCases) {
    const auto it = ours.find({p.name, p.epsilon});
    if (it == ours.end()) continue;
    const RunRecord& r = *it->second;
    for (int i = 0; i < 4; ++i) {
      const PaperIteration& q = p.iterations[i];
      std::string mine = "- | - | -";
      if (i < static_cast<int>(r.iterations.size())) {
        const IterationStats& m = r.iterations[i];
        mine = absl::StrFormat("%d → %d | %d | %s / %s", m.initial_tets, m.final_tets,
                               m.tets_with_error, Err(m.max_error), Err(m.mean_error));
      }
      absl::StrAppendFormat(&s, "| %s | %g | %d | %d → %d | %d | %s / %s | %s |\n", p.name,
                            p.epsilon, i + 1, q.initial_tets, q.final_tets, q.tets_with_error,
                            Err(q.max_error), Err(q.mean_error), mine);
    }
    absl::StrAppendFormat(&s, "| %s | %g | quality | %.4f → %.4f | | | %.4f → %.4f | | |\n", p.name,
                          p.epsilon, p.initial_quality, p.final_quality, r.initial_quality.mean,
                          r.final_quality.mean);
  }
  s += "\n";
}

void ConfigurationTable(const RunRecord& r, std::string& s) {
  if (r.iterations.empty()) return;
  s += "| configuration |";
  for (const IterationStats& it : r.iterations) absl::StrAppend(&s, " it. ", it.iteration, " |");
  s += "\n|---|";
  for (size_t i = 0; i < r.iterations.size(); ++i) s += "---|";
  s += "\n";
  for (int c = 0; c < kNumConfigurations; ++c) {
    absl::StrAppend(&s, "| ", std::string(ConfigurationName(static_cast<Configuration>(c))), " |");
    for (const IterationStats& it : r.iterations)
      absl::StrAppend(&s, " ", it.configurations[c], " |");
    s += "\n";
  }
  s += "| SP |";
  for (const IterationStats& it : r.iterations)
    absl::StrAppend(&s, " ", it.schonhardt_prisms, " |");
  s += "\n\n";
}

void IterationTable(const RunRecord& r, std::string& s) {
  s += "| iter | INT | FNT | NTwE | edges split | max error | mean error | quality min / mean | s "
       "|\n|---|---|---|---|---|---|---|---|---|\n";
  for (const IterationStats& it : r.iterations) {
    absl::StrAppendFormat(&s, "| %d | %d | %d | %d | %d of %d | %s | %s | %.4f / %.4f | %.4f |\n",
                          it.iteration, it.initial_tets, it.final_tets, it.tets_with_error,
                          it.split_edges, it.edges, Err(it.max_error), Err(it.mean_error),
                          it.quality.min, it.quality.mean, it.seconds);
  }
  absl::StrAppendFormat(&s, "| end | %d | | | | %s | %s | | |\n\n", r.final_tets,
                        Err(r.final_max_error), Err(r.final_mean_error));
}

void CaseSection(const CaseRecord& c, std::string& s) {
  absl::StrAppendFormat(&s, "### %s\n\n%s Input: %d vertices, %d tets. normCoeff %.6g.\n\n", c.name,
                        c.description, c.input_vertices, c.input_tets, c.norm_coeff);
  absl::StrAppendFormat(&s, "![%s](plots/%s.svg)\n\n", c.name, c.name);
  s += "| tetrefine run | stop | tets | midpoint max / mean | lattice max / mean | lattice points "
       "> ε | quality mean (min): before → after | uniform tets at equal lattice max / mean | "
       "time (s) | peak (MiB) |\n|---|---|---|---|---|---|---|---|---|---|\n";
  for (const RunRecord& r : c.runs) {
    absl::StrAppendFormat(
        &s,
        "| %s, ε %g, ≤ %d it. | %s after %d | %d → %d | %s / %s | %s / %s | %s | %.4f (%.4f) → "
        "%.4f (%.4f) | %s / %s | %.3f | %s |\n",
        r.scheme, r.epsilon, r.max_iterations, r.stop_reason, r.iterations.size(), r.initial_tets,
        r.final_tets, Err(r.final_max_error), Err(r.final_mean_error), Err(r.lattice.max_error),
        Err(r.lattice.mean_error), Pct(r.lattice.share_above_epsilon), r.initial_quality.mean,
        r.initial_quality.min, r.final_quality.mean, r.final_quality.min,
        Match(r.uniform_at_max, r.final_tets, c), Match(r.uniform_at_mean, r.final_tets, c),
        r.seconds, MiB(r.peak_added_bytes));
  }
  s += "\n";
  for (const Scheme& scheme : kSchemes) {
    for (const RunRecord* r : RunsToConvergence(c, scheme.name)) {
      absl::StrAppendFormat(
          &s,
          "**tetrefine %s, ε = %g** (to convergence%s): tets by "
          "configuration (Tables 3/4)\n\n",
          scheme.name, r->epsilon,
          &scheme == &kPaperScheme ? "; the 4-iteration run is its first four rows" : "");
      ConfigurationTable(*r, s);
      s += "Discrepancy by iteration (Tables 5/6; errors at the start of each iteration, quality "
           "after it)\n\n";
      IterationTable(*r, s);
    }
  }
  s += "Uniform 1:8 levels\n\n| level | tets | midpoint max | lattice max | lattice mean | "
       "quality min / mean | s |\n|---|---|---|---|---|---|---|\n";
  for (const BaselineLevel& l : c.uniform) {
    absl::StrAppendFormat(&s, "| %d | %d | %s | %s | %s | %.4f / %.4f | %.3f |\n", l.level, l.tets,
                          Err(l.midpoint_max), Err(l.lattice_max), Err(l.lattice_mean),
                          l.quality.min, l.quality.mean, l.seconds);
  }
  s += "\n";
}

}  // namespace

std::string ReportMarkdown(const ReportData& d) {
  std::string s = "# tetrefine: the paper's experiments, reproduced\n\n";
  absl::StrAppend(
      &s, "Generated by `tetrefine_reproduce` (tools/reproduce) at ", d.generated_at, " in ",
      absl::StrFormat("%.1f", d.total_seconds), " s on ", d.hardware_threads, " hardware threads",
      d.quick ? " (**--quick**: tiny cases only)" : "",
      ". Every number below is also in [results.json](results.json). To regenerate:\n\n",
      "    cmake --build build --target tetrefine_reproduce\n",
      "    build/tools/reproduce/tetrefine_reproduce --out_dir=docs/results\n\n");
  if (!d.notes.empty()) {
    s += "Notes from the run:\n\n";
    for (const std::string& n : d.notes) absl::StrAppend(&s, "- ", n, "\n");
    s += "\n";
  }
  // The demo's pictures (scripts/demo.sh; docs/images is next to docs/results, the usual
  // --out_dir), so a regenerated report keeps them.
  s += "Figures for the demo (`bash scripts/demo.sh`: the bundled 33x41x25 MRI and the 1782-tet "
       "unit cube, ε = 0.1; not part of the runs below): the plane z = 8 mm before and after "
       "refinement (`tetrefine slice`), and the largest edge-midpoint error and tets per iteration "
       "of the longest-edge and paper schemes (`tetrefine plot`).\n\n"
       "![The demo at z = 8 mm: volume, mesh interpolation and discrepancy, before and after "
       "refinement](../images/demo_slice_z8.png)\n\n"
       "![The demo's convergence: largest edge-midpoint error and tets per iteration, longest-edge "
       "and paper schemes](../images/demo_convergence.png)\n\n";
  Findings(d, s);
  Method(d, s);
  MethodsTable(d, s);
  Study(d, s);
  PaperComparison(d, s);
  s += "## Cases\n\n";
  for (const CaseRecord& c : d.cases) CaseSection(c, s);
  return s;
}

}  // namespace tetrefine::reproduce
