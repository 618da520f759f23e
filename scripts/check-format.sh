#!/usr/bin/env bash
# Fails (listing each file and line) when a tracked C++ file differs from what clang-format makes
# of it under .clang-format. Run by scripts/test.sh (so by CI) and registered with CTest
# (FormatCheck). Fix with: git ls-files '*.h' '*.cc' | xargs clang-format -i
# The clang-format is Debian 12's (14), installed by scripts/install-deps.sh: another version may
# format a few constructs differently, so this checks with that one.
set -euo pipefail
cd "$(dirname "$0")/.."
if ! command -v clang-format > /dev/null; then
  echo "check-format: clang-format is not installed (bash scripts/install-deps.sh)" >&2
  exit 1
fi
if ! git rev-parse --git-dir > /dev/null 2>&1; then
  echo "check-format: not a git checkout; nothing to list" >&2
  exit 1
fi
mapfile -t files < <(git ls-files '*.h' '*.cc')
if clang-format --dry-run --Werror "${files[@]}"; then
  echo "check-format: ${#files[@]} files match .clang-format"
else
  echo "check-format: the files above differ from clang-format's output" >&2
  exit 1
fi
