#!/usr/bin/env python3
"""CTest driver: runs the Python example client against a real tetrefine_server, then stops the
server with SIGTERM and expects a clean exit."""

import argparse
import os
import subprocess
import sys

from server_process import ServerProcess


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--server", required=True)
    parser.add_argument("--example", required=True)
    parser.add_argument("--stubs", required=True, help="directory of the generated stubs")
    args = parser.parse_args()

    with ServerProcess(args.server, ["--max_concurrent=2", "--drain_seconds=5"]) as server:
        client = subprocess.run(
            [sys.executable, args.example, f"--target={server.target}"],
            env=dict(os.environ, PYTHONPATH=args.stubs), capture_output=True, text=True,
            timeout=120)
    print(client.stdout, end="")
    print(client.stderr, end="", file=sys.stderr)
    print("".join(server.log), end="")
    if client.returncode != 0:
        print(f"example client exited with {client.returncode}", file=sys.stderr)
        return 1
    if server.exit_code != 0:
        print(f"server exited with {server.exit_code}", file=sys.stderr)
        return 1
    if not any("status=OK" in line for line in server.log):
        print("the server logged no successful Refine call", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
