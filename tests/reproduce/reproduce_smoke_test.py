#!/usr/bin/python3
"""Smoke test of tetrefine_reproduce: runs it with --quick and checks that report.md,
results.json and the plots are written, parse, and agree with each other and with the invariants
of the statistics they report (e.g. tets by configuration add up to the tets of the iteration),
and that every method has its row per case and epsilon. Plaza runs when python3-dolfinx is
installed; its script's own scores must then match core's on the same mesh."""

import argparse
import json
import os
import shutil
import subprocess
import sys
import xml.etree.ElementTree as ET


def fail(message):
    print("FAIL: " + message)
    sys.exit(1)


def check(condition, message):
    if not condition:
        fail(message)


def check_case(case, report):
    name = case["name"]
    check("### " + name in report, f"report.md has no section for case {name}")
    check(case["input_tets"] > 0, f"{name}: empty input mesh")
    check(len(case["runs"]) >= 2, f"{name}: expected a run per epsilon")
    for run in case["runs"]:
        label = f"{name} eps={run['epsilon']} max_it={run['max_iterations']}"
        check(not run["stop_reason"].startswith("error"), f"{label}: {run['stop_reason']}")
        check(run["initial_tets"] == case["input_tets"], f"{label}: initial tets")
        check(run["final_tets"] >= run["initial_tets"], f"{label}: the mesh shrank")
        check(len(run["iterations"]) <= run["max_iterations"], f"{label}: too many iterations")
        tets = run["initial_tets"]
        for it in run["iterations"]:
            check(it["initial_tets"] == tets, f"{label}: INT of iteration {it['iteration']}")
            configs = it["configurations"]
            check(sum(configs.values()) == it["initial_tets"],
                  f"{label}: configurations of iteration {it['iteration']} do not add up to INT")
            check(it["initial_tets"] - configs["0"] == it["tets_with_error"],
                  f"{label}: NTwE is not the tets outside configuration 0")
            tets = it["final_tets"]
        check(tets == run["final_tets"], f"{label}: FNT of the last iteration")
        lattice = run["lattice"]
        check(lattice["n"] == 8 and lattice["tets_sampled"] == run["final_tets"],
              f"{label}: lattice should sample every tet of a small mesh")
        check(lattice["points_sampled"] == 165 * lattice["tets_sampled"], f"{label}: 165 points")
        check(0 <= lattice["mean_error"] <= lattice["max_error"], f"{label}: lattice errors")
        for key in ("uniform_at_lattice_max", "uniform_at_lattice_mean"):
            match = run[key]
            if match["reached"]:
                level = case["uniform_levels"][match["level"]]
                check(level["tets"] == match["tets"], f"{label}: {key} tets")
    levels = case["uniform_levels"]
    check(levels and levels[0]["tets"] == case["input_tets"], f"{name}: uniform level 0")
    for a, b in zip(levels, levels[1:]):
        check(b["tets"] == 8 * a["tets"], f"{name}: uniform levels must multiply tets by 8")
    # A run reported "not reached" must really be below every level built.
    for run in case["runs"]:
        if not run["uniform_at_lattice_max"]["reached"]:
            check(all(l["lattice_max_error"] > run["lattice"]["max_error"] for l in levels),
                  f"{name}: a uniform level matched but was not reported")


def close(a, b, rel=1e-9):
    return abs(a - b) <= rel * max(abs(a), abs(b), 1e-300)


def check_methods(case, results):
    """One row per method and epsilon; Plaza either ran (and scored its result as core did) or
    says why not, the same reason in every row."""
    name = case["name"]
    expected = ["tetrefine " + s for s in results["schemes"]] + ["Plaza (DOLFINx)", "uniform 1:8"]
    rows = case["methods"]
    check([r["method"] for r in rows] == expected * len(results["epsilons"]),
          f"{name}: methods {[r['method'] for r in rows]}")
    check([r["epsilon"] for r in rows] ==
          [e for e in results["epsilons"] for _ in expected], f"{name}: method epsilons")
    levels = {l["tets"]: l for l in case["uniform_levels"]}
    for row in rows:
        label = f"{name} {row['method']} eps={row['epsilon']}"
        if row["method"] == "Plaza (DOLFINx)":
            if results["plaza"].startswith("not run: "):
                check(not row["ran"] and "not run: " + row["not_run"] == results["plaza"],
                      f"{label}: should say {results['plaza']}")
                continue
            check(row["ran"], f"{label}: {row.get('not_run')}")
            mine = row["self_report"]
            check(mine["tets"] == row["tets"], f"{label}: the script's tets")
            check(row["stop_reason"] in ("converged", "max_rounds", "tet_budget"), label)
            check(row["rounds"] <= results["max_iterations"], f"{label}: rounds over the cap")
            if row["stop_reason"] == "converged":
                check(row["midpoint_max_error"] <= row["epsilon"], f"{label}: not converged")
            # The script's numpy scores against core's, on the same mesh.
            for mine_key, core in (("midpoint_max_error", row["midpoint_max_error"]),
                                   ("lattice_max_error", row["lattice"]["max_error"]),
                                   ("lattice_mean_error", row["lattice"]["mean_error"]),
                                   ("quality_min", row["quality"]["min"]),
                                   ("quality_mean", row["quality"]["mean"])):
                check(close(mine[mine_key], core), f"{label}: {mine_key} {mine[mine_key]} "
                      f"(script) against {core} (core)")
            continue
        check(row["ran"], f"{label}: {row.get('not_run')}")
        check(0 < row["quality"]["min"] <= row["quality"]["mean"] <= 1, f"{label}: quality")
        check(0 <= row["lattice"]["mean_error"] <= row["lattice"]["max_error"], f"{label}")
        if row["method"] == "uniform 1:8":
            check(row["tets"] in levels, f"{label}: not a uniform level")
            reached = row["lattice"]["max_error"] <= row["epsilon"]
            check(row["stop_reason"] == ("lattice_reached" if reached else "tet_cap"), label)
        else:
            run = [r for r in case["runs"] if "tetrefine " + r["scheme"] == row["method"] and
                   r["epsilon"] == row["epsilon"]][-1]
            check(run["final_tets"] == row["tets"] and run["stop_reason"] == row["stop_reason"],
                  f"{label}: the row is not the scheme's run to convergence")
            if row["stop_reason"] == "converged" and row["method"] != "tetrefine certify":
                check(row["midpoint_max_error"] <= row["epsilon"], f"{label}: not converged")
            if row["stop_reason"] == "converged" and row["method"] == "tetrefine certify":
                # The certificate, checked by the tool's own lattice pass over every tet.
                check(row["lattice"]["max_error"] <= row["epsilon"], f"{label}: lattice max")
                check(close(run["certified_max_error"], row["lattice"]["max_error"]),
                      f"{label}: certified_max_error {run['certified_max_error']} against "
                      f"{row['lattice']['max_error']}")


def check_study(study):
    meshes = study["meshes"]
    check(meshes, "the section 5.1 study is empty")
    kinds = {m["kind"] for m in meshes}
    check(kinds == {"voxel-aligned", "coarse"}, f"study kinds {kinds}")
    for m in meshes:
        check(0 < m["tets_sampled"] <= m["tets"], f"{m['mesh']}: sampled tets")
        for t in m["by_threshold"]:
            parts = sum(t[k] for k in ("vertex", "edge_midpoint", "edge_other", "face", "interior"))
            check(parts == t["counted"], f"{m['mesh']}: locations do not add up")
            check(t["edge_midpoint"] <= t["near_edge_midpoint"] <= t["counted"],
                  f"{m['mesh']}: 'near' must include the midpoints themselves")


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--tool", required=True)
    parser.add_argument("--out_dir", required=True)
    args = parser.parse_args()
    shutil.rmtree(args.out_dir, ignore_errors=True)
    try:
        proc = subprocess.run([args.tool, "--quick", "--out_dir=" + args.out_dir],
                              capture_output=True, text=True, timeout=540)
    except subprocess.TimeoutExpired:
        fail("tetrefine_reproduce --quick took more than 540 s")
    sys.stderr.write(proc.stderr)
    check(proc.returncode == 0, f"exit status {proc.returncode}")

    with open(os.path.join(args.out_dir, "results.json"), encoding="utf-8") as f:
        results = json.load(f)
    with open(os.path.join(args.out_dir, "report.md"), encoding="utf-8") as f:
        report = f.read()
    check(results["schema"] == "tetrefine.reproduce/2", "schema")
    check(results["schemes"][:1] == ["paper"], "the paper scheme comes first")
    check(results["quick"] is True, "quick flag not recorded")
    check(results["epsilons"] == [0.1, 0.05], f"epsilons {results['epsilons']}")
    for heading in ("# tetrefine", "## Methods side by side", "## Section 5.1", "## Cases"):
        check(heading in report, f"report.md lacks '{heading}'")
    cases = results["cases"]
    check(len(cases) >= 2, "expected the quick cases")
    for case in cases:
        check_case(case, report)
        check_methods(case, results)
        svg = os.path.join(args.out_dir, "plots", case["name"] + ".svg")
        check(f"plots/{case['name']}.svg" in report, f"report.md does not link {svg}")
        root = ET.parse(svg).getroot()
        check(root.tag.endswith("svg"), f"{svg} is not an SVG")
        check(len(root.findall("{http://www.w3.org/2000/svg}polyline")) >= 4,
              f"{svg}: expected error and tet polylines per epsilon")
    check_study(results["max_location_study"])
    print(f"OK: {len(cases)} cases, {len(results['max_location_study']['meshes'])} study meshes, "
          f"Plaza {results['plaza']}")


if __name__ == "__main__":
    main()
