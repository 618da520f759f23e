#!/usr/bin/python3
"""Turns the raw output of bench/run_benchmarks.sh (Google Benchmark JSON and peak_memory lines)
into docs/results/benchmarks.md. Rates are recomputed here from wall-clock time and the counts
the benchmarks record, so they do not depend on how Google Benchmark normalises counters."""

import json
import os
import sys

TARGET_PER_CORE = 5e6


def load(directory, name):
    path = os.path.join(directory, name + ".json")
    if not os.path.exists(path):
        return None
    with open(path, encoding="utf-8") as f:
        return json.load(f)


def seconds(b):
    scale = {"ns": 1e-9, "us": 1e-6, "ms": 1e-3, "s": 1.0}[b["time_unit"]]
    return b["real_time"] * scale


def runs(data, prefix):
    """One entry per benchmark: of its repetitions, the fastest (other work on the machine only
    ever slows a run down, so the minimum is the best estimate of the code's own speed)."""
    if not data:
        return []
    best = {}
    for b in data["benchmarks"]:
        if (not b["name"].startswith(prefix) or b.get("run_type", "iteration") != "iteration"
                or b.get("error_occurred")):
            continue
        name = b.get("run_name", b["name"])
        if name not in best or seconds(b) < seconds(best[name]):
            best[name] = b
    return list(best.values())


def repetitions(data):
    if not data:
        return 1
    return max((b.get("repetitions", 1) for b in data["benchmarks"]), default=1)


def millions(x):
    return f"{x / 1e6:.2f} M"


def main():
    directory = sys.argv[1]
    iteration = load(directory, "iteration_bench")
    sampling = load(directory, "sampling_bench")
    subdivision = load(directory, "subdivision_bench")
    service = load(directory, "service_bench")
    context = (iteration or sampling or {}).get("context", {})
    source = "unknown source"
    source_path = os.path.join(directory, "source.txt")
    if os.path.exists(source_path):
        with open(source_path, encoding="utf-8") as f:
            source = "; ".join(line.strip() for line in f if line.strip())
    out = []
    w = out.append
    w("# tetrefine benchmarks\n")
    w("Written by `bench/summarize_benchmarks.py` from the raw output of `bash "
      "bench/run_benchmarks.sh` in [bench/](bench/). Host: "
      f"{context.get('num_cpus', '?')} CPUs at {context.get('mhz_per_cpu', '?')} MHz, "
      f"run {context.get('date', '?')}, load average at start "
      f"{', '.join(f'{x:.2f}' for x in context.get('load_avg', [])) or '?'}. "
      f"Code: {source}. Each figure is the fastest of {repetitions(iteration)} run(s); "
      "rates are wall-clock, so other work on the machine lowers them.\n")
    w("Workload (`bench/support/ripple_workload.h`): a 128x128x64 float64 volume of smooth "
      "ripples whose frequency grows with the mesh, and a structured 5-tets-per-cell mesh of the "
      "whole box; epsilon 0.05, lattice verification off. `BM_Iteration` is a whole `Refine` call "
      "with `max_iterations = 1` (validation, vertex sampling, quality, one iteration and the edge "
      "pass that measures the result); `BM_EdgeMarking` is `max_iterations = 0` (the same minus "
      "the subdivision).\n")

    headline = {}
    it_runs = runs(iteration, "BM_Iteration/")
    if it_runs:
        w("## One refinement iteration\n")
        w("| tets in | threads | wall (ms) | tets out | out/in | output tets/s | per core | "
          "speed-up over 1 thread | CPU (s) | output tets per CPU-second |")
        w("|---|---|---|---|---|---|---|---|---|---|")
        single = {}
        for b in it_runs:
            if int(b["threads"]) == 1:
                single[int(b["tets_in"])] = seconds(b)
        for b in it_runs:
            t, n_in, n_out, th = seconds(b), int(b["tets_in"]), int(b["tets_out"]), int(b["threads"])
            rate = n_out / t
            speedup = single.get(n_in, float("nan")) / t
            w(f"| {n_in:,} | {th} | {t * 1e3:.0f} | {n_out:,} | {n_out / n_in:.2f} | "
              f"{millions(rate)} | {millions(rate / th)} | {speedup:.2f} | {b['cpu_s']:.3f} | "
              f"{millions(b['out_tets_per_cpu_s'])} |")
            if 900_000 < n_in < 1_100_000:
                headline.setdefault("per_core_1m", {})[th] = rate / th
                headline.setdefault("per_cpu_s_1m", {})[th] = b["out_tets_per_cpu_s"]
                headline.setdefault("speedup_1m", {})[th] = speedup
        w("")
    em_runs = runs(iteration, "BM_EdgeMarking/")
    if em_runs:
        w("## Edge marking pass (API level)\n")
        w("| tets in | threads | wall (ms) | input tets/s |")
        w("|---|---|---|---|")
        for b in em_runs:
            t, n_in = seconds(b), int(b["tets_in"])
            w(f"| {n_in:,} | {int(b['threads'])} | {t * 1e3:.1f} | {millions(n_in / t)} |")
        w("")
    s_runs = runs(sampling, "BM_Sample")
    if s_runs:
        w("## Trilinear sampling (`Volume::Sample`, random points, one thread)\n")
        w("| voxel type | samples/s (CPU time) | ns per sample |")
        w("|---|---|---|")
        for b in s_runs:
            rate = b["items_per_second"]
            w(f"| {b['name'].split('/')[-1]} | {millions(rate)} | {1e9 / rate:.1f} |")
        w("")
    d_runs = runs(subdivision, "BM_Subdivide")
    if d_runs:
        w("## Subdividing one tet, by configuration (key, table lookup, children written)\n")
        w("| configuration | children | tets/s (CPU time) | children/s |")
        w("|---|---|---|---|")
        for b in d_runs:
            w(f"| {b.get('label', b['name'])} | {b['children_per_tet']:.0f} | "
              f"{millions(b['items_per_second'])} | {millions(b['children_per_s'])} |")
        w("")
    v_runs = runs(service, "BM_ServiceVsCore")
    if v_runs:
        w("## Service over loopback against core, same work\n")
        w("One iteration on the ~1M-tet workload, all cores on both sides; the service call "
          "streams the volume and mesh to a `tetrefine_server`-equivalent on 127.0.0.1 and the "
          "result back.\n")
        w("| tets in → out | core (s) | service (s) | service / core | server: whole call (s) | "
          "receiving input (s) | Refine (s) | the rest: sending the result (s) |")
        w("|---|---|---|---|---|---|---|---|")
        all_service = [b for b in service["benchmarks"]
                       if b["name"].startswith("BM_ServiceVsCore") and not b.get("error_occurred")
                       and b.get("run_type", "iteration") == "iteration"]
        for b in v_runs:
            # The fastest repetition of each side, as for every other figure.
            b = dict(b)
            b["core_s"] = min(x["core_s"] for x in all_service)
            b["service_s"] = min(x["service_s"] for x in all_service)
            b["service_over_core"] = b["service_s"] / b["core_s"]
            rest = b["server_call_s"] - b["server_input_s"] - b["server_refine_s"]
            w(f"| {int(b['tets_in']):,} → {int(b['tets_out']):,} | {b['core_s']:.3f} | "
              f"{b['service_s']:.3f} | {b['service_over_core']:.2f} | {b['server_call_s']:.3f} | "
              f"{b['server_input_s']:.3f} | {b['server_refine_s']:.3f} | {rest:.3f} |")
            headline["service_ratio"] = b["service_over_core"]
        w("")
    mem_path = os.path.join(directory, "peak_memory.jsonl")
    if os.path.exists(mem_path):
        with open(mem_path, encoding="utf-8") as f:
            mem = [json.loads(line) for line in f if line.strip()]
        w("## Peak memory of one Refine call\n")
        w("Measured by `bench/peak_memory` in a fresh process per row: the input is built, free "
          "heap is returned (malloc_trim), the kernel's resident high-water mark is reset "
          "(`/proc/self/clear_refs`), `Refine` runs (one iteration), and the mark's rise is "
          "read while the result is still alive. It covers the returned mesh and every "
          "temporary, not the caller's input.\n")
        w("| tets in | threads | tets out | RSS before (MiB) | peak added (MiB) | bytes per output "
          "tet |")
        w("|---|---|---|---|---|---|")
        for m in mem:
            w(f"| {m['tets_in']:,} | {m['threads']} | {m['tets_out']:,} | "
              f"{m['rss_before_bytes'] / 2**20:.0f} | {m['peak_added_bytes'] / 2**20:.0f} | "
              f"{m['peak_bytes_per_output_tet']:.0f} |")
            if 900_000 < m["tets_in"] < 1_100_000 and m["threads"] == 1:
                headline["bytes_per_tet_1m"] = m["peak_bytes_per_output_tet"]
        w("")

    w("## Headline figures (~1M input tets)\n")
    per_core = headline.get("per_core_1m", {})
    if per_core:
        one = per_core.get(1)
        verdict = "meets" if one and one >= TARGET_PER_CORE else "below"
        w(f"- Output tets per second per core: {millions(one) if one else '?'} on one thread "
          f"({verdict} the 5 M target); "
          + ", ".join(f"{millions(v)} per core on {k} threads" for k, v in per_core.items()
                      if k != 1) + ".")
        per_cpu = headline.get("per_cpu_s_1m", {})
        if per_cpu:
            w("- Output tets per CPU-second (all threads' CPU time): "
              + ", ".join(f"{millions(v)} on {k} thread{'s' if k > 1 else ''}"
                          for k, v in per_cpu.items()) + ".")
        sp = {k: v for k, v in headline.get("speedup_1m", {}).items() if k != 1}
        if sp:
            w("- Speed-up over one thread: "
              + ", ".join(f"{v:.2f} on {k} threads" for k, v in sp.items()) + ".")
    if "bytes_per_tet_1m" in headline:
        w(f"- Peak bytes per output tet: {headline['bytes_per_tet_1m']:.0f} (one thread).")
    if "service_ratio" in headline:
        w(f"- Service over loopback / core in process: {headline['service_ratio']:.2f}.")
    print("\n".join(out))


if __name__ == "__main__":
    main()
