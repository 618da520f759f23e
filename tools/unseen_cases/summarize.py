#!/usr/bin/python3
"""The unseen cases' table (run_cases.sh): per case and epsilon, tetrefine's default scheme,
--certify and the Plaza peer side by side, and the ratios issue 12's targets are stated in.

    python3 tools/unseen_cases/summarize.py RUNS_DIR
"""
import glob
import json
import os
import sys


def load(path):
    try:
        with open(path) as f:
            return json.load(f)
    except FileNotFoundError:
        return None


def main():
    runs = sys.argv[1]
    keys = sorted({os.path.basename(p).rsplit(".", 2)[0] for p in glob.glob(f"{runs}/*.json")},
                  key=lambda k: (k.rsplit("_", 1)[0], -float(k.rsplit("_", 1)[1])))
    print("| case | ε | input tets; q min / mean | default tets / iterations / stop | default "
          "midpoint; lattice max | default q min / mean | certify tets / stop; certified max | "
          "Plaza tets / rounds / stop | Plaza q min / mean | q min x | q mean x | default / "
          "Plaza | certify / Plaza |")
    print("|" + "---|" * 14)
    for key in keys:
        case, eps = key.rsplit("_", 1)
        d, c, p = (load(f"{runs}/{key}.{m}.json") for m in ("def", "cert", "plaza"))
        if d is None or c is None or p is None:
            print(f"| {case} | {eps} | missing runs |" + " |" * 11)
            continue
        qi, qf = d["quality"]["initial"], d["quality"]["final"]
        sampled = "" if d["lattice"]["tets_sampled"] >= d["output_mesh"]["tets"] else "*"
        certified = c.get("certified_max_error")
        cells = [
            case, eps, f"{d['input']['tets']:,}; {qi['min']:.3f} / {qi['mean']:.3f}",
            f"{d['output_mesh']['tets']:,} / {len(d['iterations'])} / {d['stop_reason']}",
            f"{d['final_max_error']:.4f}; {d['lattice']['max_error']:.3f}{sampled}",
            f"{qf['min']:.3f} / {qf['mean']:.3f}",
            f"{c['output_mesh']['tets']:,} / {c['stop_reason']}; "
            + ("-" if certified is None else f"{certified:.4f}"),
            f"{p['tets']:,} / {p['rounds']} / {p['stop_reason']}",
            f"{p['quality']['min']:.3f} / {p['quality']['mean']:.3f}",
            f"{qf['min'] / qi['min']:.3f}", f"{qf['mean'] / qi['mean']:.3f}",
            f"{d['output_mesh']['tets'] / p['tets']:.3f}",
            f"{c['output_mesh']['tets'] / p['tets']:.3f}",
        ]
        print("| " + " | ".join(cells) + " |")
    print("\n`*`: the lattice maximum of a 200,000-tet sample (the default verification); "
          "Plaza's is over every tet.")


if __name__ == "__main__":
    main()
