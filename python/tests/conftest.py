"""Fixtures: a real tetrefine_server on a free loopback port, the tetrefine CLI, the examples.

CTest (tests/python/CMakeLists.txt) sets TETREFINE_SERVER and TETREFINE_CLI to the built
programs; by hand, they default to <checkout>/build/server/tetrefine_server and
<checkout>/build/client/tetrefine:

    PYTHONPATH=python /usr/bin/python3 -m pytest python/tests
"""

import os
import queue
import re
import signal
import subprocess
import sys
import threading
import time

import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
EXAMPLES = os.path.join(ROOT, "examples")
EXAMPLE_VOLUME = os.path.join(EXAMPLES, "anatomical_33x41x25.nii")
EXAMPLE_MESH = os.path.join(EXAMPLES, "unit_cube_1782tets.mesh")

# The package under test comes from the checkout unless a test installs it elsewhere.
sys.path.insert(0, os.path.join(ROOT, "python"))


def _program(variable, default):
    path = os.environ.get(variable) or os.path.join(ROOT, default)
    if not os.access(path, os.X_OK):
        pytest.fail(f"{variable}: no executable at {path}; build it or set {variable}")
    return path


class Server:
    """A tetrefine_server child process; `target` is its loopback address, `log` its lines."""

    def __init__(self, binary, flags=()):
        # Metrics off: several test servers at once would fight over the default port.
        self.args = [binary, "--listen=127.0.0.1:0", "--metrics_listen=", *flags]
        self.log = []
        self.port = None

    def start(self):
        self.process = subprocess.Popen(self.args, stdout=subprocess.PIPE,
                                        stderr=subprocess.STDOUT, text=True)
        lines = queue.Queue()

        def pump():
            for line in self.process.stdout:
                self.log.append(line)
                lines.put(line)

        self.pump = threading.Thread(target=pump, daemon=True)
        self.pump.start()
        deadline = time.monotonic() + 30
        while self.port is None and time.monotonic() < deadline:
            try:
                line = lines.get(timeout=0.5)
            except queue.Empty:
                if self.process.poll() is not None:
                    break
                continue
            match = re.search(r"listening on 127\.0\.0\.1:(\d+)", line)
            if match:
                self.port = int(match.group(1))
        if self.port is None:
            self.stop()
            raise RuntimeError("tetrefine_server did not start:\n" + "".join(self.log))
        return self

    def stop(self):
        if self.process.poll() is None:
            self.process.send_signal(signal.SIGTERM)
        try:
            self.process.wait(timeout=20)
        except subprocess.TimeoutExpired:
            self.process.kill()
            self.process.wait()
        self.pump.join(timeout=5)

    @property
    def target(self):
        return f"127.0.0.1:{self.port}"

    def refine_log_lines(self):
        """The server's access log lines of Refine calls so far."""
        return [line for line in list(self.log) if "Refine peer=" in line]

    def wait_for_refine_lines(self, count, seconds=30):
        """Waits until `count` Refine calls have been logged (the log is written after the call
        ends on the server, which can be after the client has seen its status)."""
        deadline = time.monotonic() + seconds
        while len(self.refine_log_lines()) < count and time.monotonic() < deadline:
            time.sleep(0.02)
        return self.refine_log_lines()


@pytest.fixture(scope="session")
def server_binary():
    return _program("TETREFINE_SERVER", "build/server/tetrefine_server")


@pytest.fixture(scope="session")
def cli_binary():
    return _program("TETREFINE_CLI", "build/client/tetrefine")


@pytest.fixture(scope="session")
def server(server_binary):
    s = Server(server_binary, ["--max_concurrent=4", "--drain_seconds=5"]).start()
    yield s
    s.stop()


@pytest.fixture()
def own_server(server_binary):
    """A server of the test's own, for tests that read its log."""
    s = Server(server_binary, ["--max_concurrent=2", "--drain_seconds=5"]).start()
    yield s
    s.stop()


@pytest.fixture(scope="session")
def tetrefine_module():
    import tetrefine
    return tetrefine
