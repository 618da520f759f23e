#!/usr/bin/env bash
# The whole test suite from a fresh Debian 12 machine: install, check formatting, configure, build,
# run every test.
# Used as-is by .ci/run.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
bash scripts/check-format.sh  # first: a formatting change fails in seconds, not after the build
build="${TETREFINE_BUILD_DIR:-build}"
cmake -S . -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release -DTETREFINE_WERROR=ON
cmake --build "$build" -j "$(nproc)"
ctest --test-dir "$build" --output-on-failure -j "$(nproc)"
