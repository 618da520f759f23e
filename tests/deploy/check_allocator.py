#!/usr/bin/env python3
"""CTest driver: the given programs run with tcmalloc's malloc, free and operator new
(cmake/FastAllocator.cmake), not glibc's. A linker that dropped the library, or a link order
that put glibc first, would leave the programs correct but slower, and nothing else would say so.

The dynamic loader reports where each symbol is bound (LD_DEBUG=bindings); every binding of the
allocator's symbols must go to libtcmalloc, and there must be some."""

import argparse
import os
import re
import subprocess
import sys

SYMBOLS = ("malloc", "free", "calloc", "realloc", "_Znwm", "_ZdlPv")


def bindings(program):
    """[(symbol, library it is bound to)] for SYMBOLS when `program --version` runs."""
    env = dict(os.environ, LD_DEBUG="bindings")
    run = subprocess.run([program, "--version"], env=env, capture_output=True, text=True)
    if run.returncode != 0:
        sys.exit(f"FAIL: {program} --version exited with {run.returncode}: {run.stderr[-2000:]}")
    found = []
    pattern = re.compile(r"binding file \S+ \[\d+\] to (\S+) \[\d+\]: normal symbol `([^']+)'")
    for line in run.stderr.splitlines():
        match = pattern.search(line)
        if match and match.group(2) in SYMBOLS:
            found.append((match.group(2), match.group(1)))
    return found


def main():
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("programs", nargs="+")
    args = parser.parse_args()
    failures = []
    for program in args.programs:
        found = bindings(program)
        if not found:
            failures.append(f"{program}: the loader reported no binding of {', '.join(SYMBOLS)}")
        elsewhere = [(symbol, lib) for symbol, lib in found if "libtcmalloc" not in lib]
        if elsewhere:
            wrong = sorted({f"{symbol} -> {lib}" for symbol, lib in elsewhere})
            failures.append(f"{program}: bound elsewhere than tcmalloc: {'; '.join(wrong)}")
        print(f"{program}: {len(found)} bindings of the allocator's symbols, "
              f"{len(found) - len(elsewhere)} to tcmalloc")
    if failures:
        sys.exit("FAIL:\n  " + "\n  ".join(failures))


if __name__ == "__main__":
    main()
