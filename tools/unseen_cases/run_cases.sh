#!/usr/bin/env bash
# Runs the unseen cases (make_cases.py) at epsilon 0.1 and 0.05: tetrefine's default scheme,
# --certify, and the Plaza peer (bench/peers/plaza_refine.py, DOLFINx), one at a time on one
# thread, each with a 3 M-tet budget and 32 iterations at most, then prints the summary table
# (summarize.py) that docs/results/unseen_cases.md holds.
#
# Usage: bash tools/unseen_cases/run_cases.sh CASES_DIR RUNS_DIR [build-dir] [CASE ...]
#   (from the repository's root; the peer needs python3-dolfinx: bench/peers/install-peers.sh)
# All eleven cases take about 25 minutes on 2 cores, most of it in the Plaza peer.
set -euo pipefail
cases_dir="$1"
runs_dir="$2"
build="${3:-build}"
shift $(($# < 3 ? $# : 3))
tetrefine="$build/client/tetrefine"
plaza="bench/peers/plaza_refine.py"
mkdir -p "$runs_dir"
names=("$@")
if [ ${#names[@]} -eq 0 ]; then
  mapfile -t names < <(ls "$cases_dir")
fi
for c in "${names[@]}"; do
  for e in 0.1 0.05; do
    d="$cases_dir/$c"
    b="$runs_dir/${c}_$e"
    for mode in def cert; do
      extra=()
      [ "$mode" = cert ] && extra=(--certify)
      "$tetrefine" refine --volume "$d/vol.nii.gz" --mesh "$d/mesh.vtu" --epsilon "$e" \
        --threads 1 --max-tets 3000000 --max-iterations 32 "${extra[@]}" --quiet \
        --stats-json "$b.$mode.json" --output "$b.$mode.vtu" >"$b.$mode.out"
    done
    OMP_NUM_THREADS=1 /usr/bin/python3 "$plaza" --case "$d" --epsilon "$e" --max-rounds 32 \
      --max-tets 3000000 --quiet --output "$b.plaza.json" >"$b.plaza.out"
    echo "$c $e done" >&2
  done
done
/usr/bin/python3 "$(dirname "$0")/summarize.py" "$runs_dir"
