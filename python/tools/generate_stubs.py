#!/usr/bin/env python3
"""Generates the package's gRPC stubs (python/tetrefine/v1/tetrefine_pb2*.py) from
proto/tetrefine/v1/tetrefine.proto, or with --check fails when the shipped ones differ.

The stubs are shipped so that `pip install ./python` needs no compiler. Debian's
python3-grpc-tools cannot compile proto3 `optional`, so this uses protoc and grpc_python_plugin
(Debian packages protobuf-compiler and protobuf-compiler-grpc). After changing the proto:

    python3 python/tools/generate_stubs.py          # rewrite the shipped stubs
    python3 python/tools/generate_stubs.py --check  # what CTest runs (PythonStubsCurrent)
"""

import argparse
import difflib
import os
import shutil
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
PROTO_DIR = os.path.join(ROOT, "proto")
PROTO = "tetrefine/v1/tetrefine.proto"
PACKAGE_DIR = os.path.join(ROOT, "python", "tetrefine", "v1")
STUBS = ("tetrefine_pb2.py", "tetrefine_pb2_grpc.py")


def generate(protoc, plugin, proto_dir, out_dir):
    """Runs protoc on `proto_dir`/PROTO; returns {stub name: bytes}."""
    subprocess.run([protoc, f"-I{proto_dir}", f"--python_out={out_dir}",
                    f"--plugin=protoc-gen-grpc_python={plugin}", f"--grpc_python_out={out_dir}",
                    os.path.join(proto_dir, PROTO)], check=True)
    stubs = {}
    for name in STUBS:
        with open(os.path.join(out_dir, "tetrefine", "v1", name), "rb") as f:
            stubs[name] = f.read()
    return stubs


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--check", action="store_true",
                        help="compare with the shipped stubs instead of writing them")
    parser.add_argument("--protoc", default=shutil.which("protoc"))
    parser.add_argument("--plugin", default=shutil.which("grpc_python_plugin"))
    parser.add_argument("--proto-dir", default=PROTO_DIR, help="root of the proto imports")
    parser.add_argument("--package-dir", default=PACKAGE_DIR, help="where the stubs live")
    args = parser.parse_args()
    for name, path in (("--protoc", args.protoc), ("--plugin", args.plugin)):
        if not path or not os.access(path, os.X_OK):
            print(f"generate_stubs: {name}: no executable {path or '(not found on PATH)'}; "
                  "install protobuf-compiler and protobuf-compiler-grpc", file=sys.stderr)
            return 2

    with tempfile.TemporaryDirectory() as out_dir:
        stubs = generate(args.protoc, args.plugin, args.proto_dir, out_dir)
    stale = []
    for name, text in stubs.items():
        path = os.path.join(args.package_dir, name)
        current = open(path, "rb").read() if os.path.exists(path) else b""
        if current == text:
            continue
        if not args.check:
            with open(path, "wb") as f:
                f.write(text)
            print(f"wrote {os.path.relpath(path, ROOT)}")
            continue
        stale.append(name)
        diff = difflib.unified_diff(current.decode(errors="replace").splitlines(),
                                    text.decode(errors="replace").splitlines(),
                                    f"shipped/{name}", f"generated/{name}", lineterm="", n=0)
        print("\n".join(list(diff)[:20]))
    if stale:
        print(f"generate_stubs: {', '.join(stale)} in python/tetrefine/v1 differ from "
              f"{PROTO}; run: python3 python/tools/generate_stubs.py", file=sys.stderr)
        return 1
    if args.check:
        print(f"the shipped stubs match {PROTO}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
