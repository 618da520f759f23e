"""A tetrefine_server child process on a free loopback port, for the Python-driven tests."""

import queue
import re
import signal
import subprocess
import threading
import time


class ServerProcess:
    """Starts `binary` with `flags` plus --listen=127.0.0.1:0 and learns the port from its log.

    Leaving the context sends SIGTERM and records the exit code in `exit_code`."""

    def __init__(self, binary, flags=()):
        self.args = [binary, "--listen=127.0.0.1:0", *flags]
        self.port = None
        self.exit_code = None
        self.log = []

    def __enter__(self):
        self.process = subprocess.Popen(self.args, stdout=subprocess.PIPE,
                                        stderr=subprocess.STDOUT, text=True)
        lines = queue.Queue()

        def pump():
            for line in self.process.stdout:
                self.log.append(line)
                lines.put(line)

        self.pump = threading.Thread(target=pump, daemon=True)
        self.pump.start()
        # Port 0 lets the server pick a free port; it logs the one it bound.
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
            self.exit_code = self.process.wait(timeout=20)
        except subprocess.TimeoutExpired:
            self.process.kill()
            self.exit_code = "killed after ignoring SIGTERM"
        self.pump.join(timeout=5)

    def __exit__(self, *exc):
        self.stop()
        return False

    @property
    def target(self):
        return f"127.0.0.1:{self.port}"
