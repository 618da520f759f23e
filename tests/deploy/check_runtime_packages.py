#!/usr/bin/env python3
"""CTest driver: every shared library the given binaries load (per ldd) belongs to a Debian package
that the Dockerfile's runtime stage installs, so the image runs what this build produced.

No Docker engine is needed: the build machine is Debian 12 like the image, so the package that
owns a library here is the package that provides it there."""

import argparse
import os
import re
import subprocess
import sys

sys.dont_write_bytecode = True  # no __pycache__ in the source tree

import dockerfile_parse

# In every debian:bookworm image (essential): the C library and its loader.
BASE_IMAGE_PACKAGES = {"libc6"}


def libraries(binary):
    """Absolute paths ldd resolves for `binary`; fails on a library it cannot find."""
    out = subprocess.run(["ldd", binary], check=True, capture_output=True, text=True).stdout
    paths = []
    for line in out.splitlines():
        if "not found" in line:
            sys.exit(f"FAIL: {binary}: {line.strip()}")
        match = re.search(r"=>\s*(/\S+)", line) or re.match(r"\s*(/\S+)", line)
        if match:
            paths.append(match.group(1))
    return paths


def owners(paths):
    """{path: owning Debian package} for each path (as given or resolved) that dpkg knows. One
    dpkg call for all: it is slow to start."""
    candidates = sorted({c for p in paths for c in (p, os.path.realpath(p))})
    result = subprocess.run(["dpkg", "-S", *candidates], capture_output=True, text=True)
    by_file = {}
    for line in result.stdout.splitlines():
        if line.startswith("diversion "):
            continue
        packages, _, file = line.partition(": ")
        by_file[file.strip()] = packages.split(",")[0].split(":")[0].strip()
    found = {}
    for p in paths:
        package = by_file.get(p) or by_file.get(os.path.realpath(p))
        if package:
            found[p] = package
    return found


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--dockerfile", required=True)
    parser.add_argument("binaries", nargs="+")
    args = parser.parse_args()

    with open(args.dockerfile) as f:
        stages = dockerfile_parse.parse(f.read())
    runtime = stages[-1]
    installed = set(runtime.apt_packages())
    if not installed:
        sys.exit("FAIL: the runtime stage installs no packages")
    provided = installed | BASE_IMAGE_PACKAGES

    failures, needed = [], set()
    loaded = {binary: libraries(binary) for binary in args.binaries}
    package_of = owners([lib for libs in loaded.values() for lib in libs])
    for binary, libs in loaded.items():
        for lib in libs:
            package = package_of.get(lib)
            if package is None:
                failures.append(f"{os.path.basename(binary)}: {lib} belongs to no package")
            elif package not in provided:
                failures.append(f"{os.path.basename(binary)}: {lib} is in {package}, "
                                "which the runtime stage does not install")
            else:
                needed.add(package)
    for line in failures:
        print("FAIL:", line)
    print(f"runtime stage installs: {' '.join(sorted(installed))}")
    print(f"libraries come from: {' '.join(sorted(needed))}")
    unused = installed - needed - {"ca-certificates"}
    if unused:
        print(f"note: installed but not loaded by these binaries: {' '.join(sorted(unused))}")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
