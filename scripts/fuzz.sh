#!/usr/bin/env bash
# Fuzzes every libFuzzer target in fuzz/ for a bounded time: installs clang (TETREFINE_WITH_FUZZ=1),
# builds build-fuzz with clang-14 and ASan + UBSan + libFuzzer, then runs each target on a copy
# of its seed corpus (fuzz/corpus/<target>), as many targets at once as there are cores.
# Exits non-zero when any target finds a crash, a leak, undefined behaviour or a timeout; the
# input that did it is kept in build-fuzz/fuzz-work/<target>/findings/.
#
#   scripts/fuzz.sh [seconds-per-target] [target...]     (default 20 s, every target)
#
# A finding becomes a regression test by copying its input into fuzz/corpus/<target>/: the
# corpus replay tests (ctest -R FuzzCorpus) run every corpus file in the normal build.
set -euo pipefail
cd "$(dirname "$0")/.."
TETREFINE_WITH_FUZZ=1 bash scripts/install-deps.sh

seconds="${1:-20}"
shift || true
build=build-fuzz
export CC=clang-14 CXX=clang++-14
# A unity build, like the test and sanitizer builds: 105 compiles one source at a time took about
# 150 s of CI's 30 minutes (2026-11-24). A missing #include that a batch neighbour hides shows up
# in the one-source-at-a-time build the README gives for day-to-day work.
cmake -S . -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_UNITY_BUILD=ON \
  -DTETREFINE_BUILD_FUZZ=ON -DTETREFINE_BUILD_TESTS=OFF -DTETREFINE_BUILD_BENCH=OFF \
  -DTETREFINE_SANITIZE=fuzzer-no-link,address,undefined \
  -DCMAKE_CXX_FLAGS="-fno-sanitize-recover=undefined" >/dev/null
cmake --build "$build" --target fuzz_all -j "$(nproc)"

if [ $# -gt 0 ]; then
  targets=("$@")
else
  targets=()
  for source in fuzz/*_fuzzer.cc; do
    name=$(basename "$source" _fuzzer.cc)
    targets+=("$name")
  done
fi

export ASAN_OPTIONS="abort_on_error=1:detect_leaks=1:allocator_may_return_null=0"
export UBSAN_OPTIONS="halt_on_error=1:print_stacktrace=1"

run_one() {
  local target=$1
  local work="$build/fuzz-work/$target"
  rm -rf "$work"
  mkdir -p "$work/corpus" "$work/findings"
  cp fuzz/corpus/"$target"/* "$work/corpus/"
  # -timeout: one input running longer than this counts as a finding (a hang).
  "$build/fuzz/fuzz_$target" -max_total_time="$seconds" -timeout=15 -rss_limit_mb=2560 \
    -max_len=16384 -print_final_stats=1 -artifact_prefix="$work/findings/" \
    "$work/corpus" >"$work/log" 2>&1
}

pids=()
names=()
for target in "${targets[@]}"; do
  if [ ! -d "fuzz/corpus/$target" ]; then
    echo "no corpus fuzz/corpus/$target" >&2
    exit 2
  fi
  while [ "$(jobs -rp | wc -l)" -ge "$(nproc)" ]; do sleep 0.2; done
  echo "fuzzing $target for ${seconds}s"
  run_one "$target" &
  pids+=($!)
  names+=("$target")
done

failed=0
printf '\n%-12s %12s %10s  %s\n' target executions corpus result
for i in "${!pids[@]}"; do
  target=${names[$i]}
  log="$build/fuzz-work/$target/log"
  if wait "${pids[$i]}"; then result=ok; else result=FAILED; failed=1; fi
  execs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -1)
  corpus=$(find "$build/fuzz-work/$target/corpus" -type f | wc -l)
  printf '%-12s %12s %10s  %s\n' "$target" "${execs:-?}" "$corpus" "$result"
  if [ "$result" = FAILED ]; then
    echo "---- $target: last lines of $log" >&2
    tail -n 60 "$log" >&2
    ls -l "$build/fuzz-work/$target/findings" >&2
  fi
done
exit "$failed"
