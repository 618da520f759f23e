#!/usr/bin/env bash
# Runs the benchmarks and the peak-memory measurements, and writes their raw output to
# docs/results/bench/ and a summary to docs/results/benchmarks.md.
# Usage: bash bench/run_benchmarks.sh [build-dir]   (default: build; takes a few minutes)
# Run it on a quiet machine: the summary records the load average, and other work on the
# cores shows up directly in the wall-clock rates.
set -euo pipefail
cd "$(dirname "$0")/.."
build="${1:-build}"
out=docs/results/bench
mkdir -p "$out"
# Which code was measured: the commit, and whether core/ differed from it.
{
  echo "commit $(git rev-parse --short HEAD 2>/dev/null || echo unknown)"
  if [ -n "$(git status --porcelain -- core 2>/dev/null)" ]; then
    echo "core/ had uncommitted changes"
  else
    echo "core/ as committed"
  fi
} >"$out/source.txt"
cmake --build "$build" --target sampling_bench subdivision_bench iteration_bench service_bench \
  peak_memory
# Three repetitions each; the summary keeps the fastest, which other work on the machine disturbs
# least.
for b in sampling_bench subdivision_bench iteration_bench service_bench; do
  echo "== $b" >&2
  "$build/bench/$b" --benchmark_out="$out/$b.json" --benchmark_out_format=json \
    --benchmark_counters_tabular=true --benchmark_repetitions=3
done
# One fresh process per measurement: the high-water mark then covers exactly one Refine call.
: >"$out/peak_memory.jsonl"
for cells in 58 126; do
  for threads in 1 "$(nproc)"; do
    echo "== peak_memory --cells=$cells --threads=$threads" >&2
    "$build/bench/peak_memory" --cells="$cells" --threads="$threads" >>"$out/peak_memory.jsonl"
  done
done
/usr/bin/python3 bench/summarize_benchmarks.py "$out" >docs/results/benchmarks.md
echo "wrote docs/results/benchmarks.md" >&2
