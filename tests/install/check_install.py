#!/usr/bin/env python3
"""CTest driver: `cmake --install` into a fresh prefix puts the programs, the libraries, their
headers and the proto where cmake/Install.cmake says, the programs run from there, and the
installed headers need no header that was left out."""

import argparse
import filecmp
import glob
import os
import re
import subprocess
import sys
import tempfile


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--build", required=True, help="the build directory to install")
    parser.add_argument("--source", required=True)
    parser.add_argument("--cxx", required=True, help="C++ compiler for the header check")
    parser.add_argument("--include", action="append", default=[],
                        help="include directories of the dependencies (Abseil)")
    args = parser.parse_args()
    failures = []
    with tempfile.TemporaryDirectory() as prefix:
        done = subprocess.run(["cmake", "--install", args.build, "--prefix", prefix],
                              capture_output=True, text=True)
        if done.returncode != 0:
            print(done.stdout, done.stderr)
            return 1
        for program in ("bin/tetrefine", "bin/tetrefine_server"):
            path = os.path.join(prefix, program)
            if not os.access(path, os.X_OK):
                failures.append(f"{program}: missing or not executable")
        version = subprocess.run([os.path.join(prefix, "bin/tetrefine"), "--version"],
                                 capture_output=True, text=True)
        if version.returncode != 0 or not version.stdout.startswith("tetrefine "):
            failures.append(f"bin/tetrefine --version: {version.stdout!r} {version.stderr!r}")
        for library in ("libtetrefine_core.a", "libtetrefine_io.a"):
            if not glob.glob(os.path.join(prefix, "lib*", library)):
                failures.append(f"lib/{library}: missing")
        proto = os.path.join(prefix, "share/tetrefine/proto/tetrefine/v1/tetrefine.proto")
        source_proto = os.path.join(args.source, "proto/tetrefine/v1/tetrefine.proto")
        if not os.path.exists(proto) or not filecmp.cmp(proto, source_proto, shallow=False):
            failures.append("share/tetrefine/proto/tetrefine/v1/tetrefine.proto: missing or "
                            "not the source's")
        include = os.path.join(prefix, "include", "tetrefine")
        for part in ("core", "client/io"):
            source = sorted(os.path.basename(p)
                            for p in glob.glob(os.path.join(args.source, part, "*.h")))
            installed = sorted(os.path.basename(p)
                               for p in glob.glob(os.path.join(include, part, "*.h")))
            if not source or source != installed:
                failures.append(f"include/tetrefine/{part}: {installed} != source {source}")
        # Every project header an installed header includes is installed too, and all of them
        # compile together against the installed tree only (plus the dependencies). One
        # translation unit: a compile per header costs minutes for what the include scan shows.
        headers = sorted(glob.glob(os.path.join(include, "**", "*.h"), recursive=True))
        project_dirs = {d for d in os.listdir(args.source)
                        if os.path.isdir(os.path.join(args.source, d))}
        for header in headers:
            for line in open(header):
                match = re.match(r'\s*#\s*include\s+"([^"]+)"', line)
                ours = match and match.group(1).split("/")[0] in project_dirs
                if ours and not os.path.exists(os.path.join(include, match.group(1))):
                    failures.append(f"{os.path.relpath(header, prefix)} includes "
                                    f"{match.group(1)}, which is not installed")
        all_headers = os.path.join(prefix, "all_headers.cc")
        with open(all_headers, "w") as f:
            f.writelines(f'#include "{os.path.relpath(h, include)}"\n' for h in headers)
        compile_only = [args.cxx, "-std=c++20", "-fsyntax-only", "-I", include,
                        *[f"-I{d}" for d in args.include], all_headers]
        done = subprocess.run(compile_only, capture_output=True, text=True)
        if done.returncode != 0:
            failures.append(f"the installed headers do not compile: "
                            f"{done.stderr.splitlines()[:5]}")
        print(f"installed into {prefix}: 2 programs, 2 libraries, {len(headers)} headers, "
              "the proto")
    for failure in failures:
        print("FAIL:", failure)
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
