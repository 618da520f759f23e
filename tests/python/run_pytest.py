#!/usr/bin/env python3
"""CTest driver for the Python package's pytest suite (python/tests).

Usage: run_pytest.py --server BIN --cli BIN -- [pytest arguments]

Fails when pytest collects no test (its exit code 5): an empty run proves nothing. Runs with the
interpreter that runs this script (CTest uses Debian's /usr/bin/python3, whose python3-grpcio,
python3-protobuf, python3-numpy, python3-nibabel, python3-meshio and python3-pytest the tests
need) and writes no cache or bytecode into the checkout.
"""

import argparse
import os
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--server", required=True, help="tetrefine_server binary")
    parser.add_argument("--cli", required=True, help="tetrefine binary")
    parser.add_argument("pytest_args", nargs="*")
    args = parser.parse_args()
    missing = []
    for module in ("pytest", "grpc", "google.protobuf", "numpy", "nibabel", "meshio"):
        try:
            __import__(module)
        except ImportError:
            missing.append(module)
    if missing:
        print(f"run_pytest: {sys.executable} lacks {', '.join(missing)}; run "
              "scripts/install-deps.sh", file=sys.stderr)
        return 1
    env = dict(os.environ, TETREFINE_SERVER=args.server, TETREFINE_CLI=args.cli,
               PYTHONDONTWRITEBYTECODE="1", PYTHONPATH=os.path.join(ROOT, "python"))
    command = [sys.executable, "-m", "pytest", "-p", "no:cacheprovider", "-v", "-rs",
               "--rootdir", os.path.join(ROOT, "python", "tests"), *args.pytest_args]
    code = subprocess.call(command, env=env, cwd=os.path.join(ROOT, "python", "tests"))
    if code == 5:
        print("run_pytest: pytest collected no tests", file=sys.stderr)
        return 1
    return code


if __name__ == "__main__":
    sys.exit(main())
