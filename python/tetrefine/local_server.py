"""A tetrefine_server of your own, for a pipeline on one machine.

The CLI runs the service embedded when no server is named; this is the Python equivalent: a
tetrefine_server child process on a free loopback port, reachable only with a token made for it,
stopped when the `with` block ends:

    with tetrefine.LocalServer() as server, server.client() as client:
        result = client.refine(volume, spacing, origin, points, tets, epsilon=0.1)
"""

import os
import queue
import re
import secrets
import shutil
import signal
import subprocess
import tempfile
import threading
import time

import grpc

from tetrefine.client import Client
from tetrefine.errors import TetrefineError, invalid

# Where the server says which port it bound (server/main.cc's start-up line).
_LISTENING = re.compile(r"listening on 127\.0\.0\.1:(\d+)")


def find_server_binary(binary=None):
    """The tetrefine_server to run: `binary`, else $TETREFINE_SERVER, else the one on the PATH
    (what `cmake --install` puts in <prefix>/bin). A TetrefineError (FAILED_PRECONDITION) naming
    what was tried when none is executable."""
    tried = []
    for source, path in (("binary", binary), ("TETREFINE_SERVER", os.environ.get(
            "TETREFINE_SERVER")), ("PATH", shutil.which("tetrefine_server"))):
        if not path:
            continue
        if os.path.isfile(path) and os.access(path, os.X_OK):
            return path
        tried.append(f"{source}: {path}")
    detail = "; ".join(tried) if tried else (
        "no binary= given, TETREFINE_SERVER unset, none on the PATH")
    raise TetrefineError(
        grpc.StatusCode.FAILED_PRECONDITION,
        f"LocalServer: no executable tetrefine_server ({detail}); install tetrefine "
        "(cmake --install build) or pass binary= / set TETREFINE_SERVER to the built "
        "build/server/tetrefine_server")


class LocalServer:
    """A tetrefine_server child process on a free loopback port.

    Args:
      binary: path of tetrefine_server (default: find_server_binary()).
      flags: more server flags, e.g. ("--threads=2", "--max_concurrent=2"); see
        `tetrefine_server --help`.
      start_timeout: seconds to wait for the server to listen.

    Attributes:
      target: "127.0.0.1:PORT", the port the server chose.
      token: the bearer token every call must carry (a random one, written to a file only this
        user can read): other users of the machine cannot use the server.
      log: the server's output lines so far (its log goes to stderr, which is kept here).

    Use as a context manager, or call close() (SIGTERM: calls in flight are cancelled after 2 s,
    the server's --drain_seconds here; the process is killed if it has not ended 40 s later).
    client() gives a Client with the token; close the clients before the server, or let the
    `with` statement do it.
    """

    def __init__(self, binary=None, *, flags=(), start_timeout=30.0):
        if isinstance(flags, str) or not all(isinstance(f, str) for f in flags):
            raise invalid("flags", "expected a sequence of strings such as (\"--threads=2\",)")
        if not isinstance(start_timeout, (int, float)) or not start_timeout > 0:
            raise invalid("start_timeout", f"expected a positive number, got {start_timeout!r}")
        self._binary = find_server_binary(binary)
        self.token = secrets.token_hex(16)
        self.log = []
        self.target = None
        self._dir = tempfile.TemporaryDirectory(prefix="tetrefine_server_")
        token_file = os.path.join(self._dir.name, "tokens")
        with open(os.open(token_file, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600), "w") as f:
            f.write(f"local {self.token}\n")
        # Metrics off: its default port would clash with a second local server. A short drain:
        # close() comes when the pipeline is done with the server (or interrupted), and the
        # calls still in flight are its own; `flags` come last, so they can change both.
        # The server ends when its standard input does: this process holds the pipe's write end,
        # and the kernel closes it however this process ends. Killed by SIGTERM (what timeout,
        # SLURM and Kubernetes send) or SIGKILL, a pipeline left its server running for good,
        # with a port, its memory and the token file (an outside review, 2026-11-29).
        args = [self._binary, "--listen=127.0.0.1:0", "--metrics_listen=", "--drain_seconds=2",
                "--exit_when_stdin_closes", f"--token_file={token_file}", *flags]
        try:
            self._process = subprocess.Popen(args, stdin=subprocess.PIPE,
                                             stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                                             text=True, errors="replace")
        except OSError as error:
            self._dir.cleanup()
            raise TetrefineError(grpc.StatusCode.FAILED_PRECONDITION,
                                 f"LocalServer: cannot run {self._binary}: {error}") from None
        lines = queue.Queue()

        def pump():
            # Read to the end, so that a chatty server never blocks on a full pipe.
            for line in self._process.stdout:
                self.log.append(line)
                lines.put(line)
            lines.put(None)

        threading.Thread(target=pump, daemon=True).start()
        deadline = time.monotonic() + start_timeout
        port = None
        output_ended = False
        while port is None:
            left = deadline - time.monotonic()
            if left <= 0:
                break
            try:
                line = lines.get(timeout=min(left, 0.5))
            except queue.Empty:
                continue
            if line is None:  # the process closed its output: it is ending
                output_ended = True
                break
            match = _LISTENING.search(line)
            if match:
                port = int(match.group(1))
        if port is None:
            # Its output ends before it has exited: wait for the status rather than poll, which
            # could still see it running and blame a timeout that never happened.
            exited = self._process.poll()
            if exited is None and output_ended:
                try:
                    exited = self._process.wait(timeout=10)
                except subprocess.TimeoutExpired:
                    exited = None
            self._stop()
            reason = (f"exited with status {exited}" if exited is not None else
                      f"did not listen within {start_timeout} s")
            log = "".join(self.log[-20:]).strip()
            raise TetrefineError(grpc.StatusCode.UNAVAILABLE,
                                 f"LocalServer: {self._binary} {reason}" +
                                 (f"; its last lines:\n{log}" if log else ""))
        self.target = f"127.0.0.1:{port}"
        # The server read its tokens at start and never again: the file goes now, so that a
        # killed pipeline leaves none behind.
        self._dir.cleanup()

    def client(self):
        """A Client of this server, with its token."""
        if self._process.poll() is not None:
            raise TetrefineError(grpc.StatusCode.FAILED_PRECONDITION,
                                 "LocalServer: the server has stopped")
        return Client(self.target, token=self.token)

    def _stop(self, timeout=40.0):
        if self._process.poll() is None:
            self._process.send_signal(signal.SIGTERM)
            try:
                self._process.wait(timeout=timeout)
            except subprocess.TimeoutExpired:
                self._process.kill()
                self._process.wait()
        if self._process.stdin is not None:
            self._process.stdin.close()
        self._dir.cleanup()

    def close(self):
        """Stops the server (SIGTERM, then SIGKILL after 40 s) and removes its token file."""
        self._stop()

    @property
    def running(self):
        return self._process.poll() is None

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
        return False

    def __del__(self):
        # A server left running outlives the pipeline otherwise.
        process = getattr(self, "_process", None)
        if process is not None and process.poll() is None:
            process.kill()
