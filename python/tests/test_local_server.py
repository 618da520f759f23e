"""tetrefine.LocalServer: a tetrefine_server of the pipeline's own, as the CLI embeds one."""

import os
import signal
import subprocess
import sys
import threading
import time

import grpc
import meshio
import nibabel
import numpy as np
import pytest

import tetrefine
from conftest import EXAMPLE_MESH, EXAMPLE_VOLUME
from test_refine import _heavy_input, assert_same_as_cli_output, run_cli


def test_refines_as_the_cli_does_with_its_embedded_service(server_binary, cli_binary, tmp_path):
    output = tmp_path / "cli.vtu"
    # No --server: the CLI runs the service in its own process.
    run_cli(cli_binary, "refine", "--volume", EXAMPLE_VOLUME, "--mesh", EXAMPLE_MESH,
            "--fit-mesh-to-volume", "--epsilon", "0.1", "--quiet", "--output", str(output))
    volume = tetrefine.volume_from_nibabel(nibabel.load(EXAMPLE_VOLUME))
    mesh = tetrefine.mesh_from_meshio(meshio.read(EXAMPLE_MESH))
    points = tetrefine.fit_to_volume(mesh.points, volume)
    with tetrefine.LocalServer(server_binary) as server, server.client() as client:
        assert server.running
        assert server.target.startswith("127.0.0.1:")
        result = client.refine(volume.data, volume.spacing, volume.origin, points, mesh.tets, 0.1)
    assert not server.running
    assert result.stop_reason == "converged"
    assert_same_as_cli_output(result, output)


def test_only_callers_with_its_token_are_served(server_binary):
    with tetrefine.LocalServer(server_binary) as server:
        with tetrefine.Client(server.target) as stranger:
            with pytest.raises(tetrefine.TetrefineError) as refused:
                stranger.server_info()
        assert refused.value.code == grpc.StatusCode.UNAUTHENTICATED
        with server.client() as client:
            assert client.server_info().version


def test_the_token_file_is_gone_once_the_server_listens(server_binary):
    # The server reads it at start only; removed then, a killed pipeline leaves none behind.
    server = tetrefine.LocalServer(server_binary)
    try:
        token_file = next(a.split("=", 1)[1] for a in server._process.args
                          if a.startswith("--token_file="))
        assert not os.path.exists(token_file)
        assert not os.path.exists(os.path.dirname(token_file))
        with server.client() as client:
            assert client.server_info().version
    finally:
        server.close()
    assert not server.running
    with pytest.raises(tetrefine.TetrefineError) as stopped:
        server.client()
    assert stopped.value.code == grpc.StatusCode.FAILED_PRECONDITION
    assert "stopped" in stopped.value.details


_PIPELINE = """
import sys, time
import tetrefine
server = tetrefine.LocalServer(sys.argv[1])
print(server._process.pid, flush=True)
time.sleep(600)
"""


def _gone(pid, within):
    deadline = time.monotonic() + within
    while time.monotonic() < deadline:
        try:
            os.kill(pid, 0)
        except ProcessLookupError:
            return True
        # A zombie is gone for our purpose: its parent (the killed pipeline) will never reap it.
        try:
            with open(f"/proc/{pid}/stat") as f:
                if f.read().split(") ", 1)[1].startswith("Z"):
                    return True
        except FileNotFoundError:
            return True
        time.sleep(0.1)
    return False


@pytest.mark.parametrize("signal_number", [signal.SIGKILL, signal.SIGTERM])
def test_a_killed_pipeline_leaves_no_server_running(server_binary, signal_number):
    # Killed by SIGTERM (timeout, SLURM, Kubernetes) or SIGKILL, a pipeline left its server
    # running for good (an outside review, 2026-11-29): the server now ends with its stdin pipe.
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(sys.path))
    pipeline = subprocess.Popen([sys.executable, "-c", _PIPELINE, server_binary],
                                stdout=subprocess.PIPE, text=True, env=env)
    try:
        server_pid = int(pipeline.stdout.readline())
        os.kill(server_pid, 0)  # running
        pipeline.send_signal(signal_number)
        pipeline.wait(timeout=30)
        assert _gone(server_pid, within=20), f"tetrefine_server {server_pid} outlived its pipeline"
    finally:
        if pipeline.poll() is None:
            pipeline.kill()


def test_two_servers_at_once_get_their_own_ports(server_binary):
    with tetrefine.LocalServer(server_binary) as a, tetrefine.LocalServer(server_binary) as b:
        assert a.target != b.target
        assert a.token != b.token
        with a.client() as ca, b.client() as cb:
            assert ca.server_info().version == cb.server_info().version


def test_flags_reach_the_server(server_binary):
    with tetrefine.LocalServer(server_binary, flags=["--max_concurrent=1"]) as server:
        with server.client() as client:
            assert client.server_info().limits.max_concurrent_refinements == 1


def test_a_server_that_cannot_start_says_why(server_binary):
    with pytest.raises(tetrefine.TetrefineError) as failed:
        tetrefine.LocalServer(server_binary, flags=["--no_such_flag=1"])
    assert failed.value.code == grpc.StatusCode.UNAVAILABLE
    assert "exited with status" in failed.value.details
    assert "no_such_flag" in failed.value.details


def test_without_a_binary_the_error_says_what_was_tried(monkeypatch, tmp_path):
    monkeypatch.setenv("TETREFINE_SERVER", str(tmp_path / "missing_server"))
    monkeypatch.setenv("PATH", str(tmp_path))
    with pytest.raises(tetrefine.TetrefineError) as missing:
        tetrefine.LocalServer()
    assert missing.value.code == grpc.StatusCode.FAILED_PRECONDITION
    assert f"TETREFINE_SERVER: {tmp_path / 'missing_server'}" in missing.value.details
    assert "cmake --install" in missing.value.details
    monkeypatch.delenv("TETREFINE_SERVER")
    with pytest.raises(tetrefine.TetrefineError) as nothing:
        tetrefine.find_server_binary()
    assert "TETREFINE_SERVER unset, none on the PATH" in nothing.value.details


def test_the_binary_is_found_on_the_path_and_in_the_environment(server_binary, monkeypatch):
    monkeypatch.delenv("TETREFINE_SERVER", raising=False)
    monkeypatch.setenv("PATH", os.path.dirname(server_binary))
    assert tetrefine.find_server_binary() == server_binary
    monkeypatch.setenv("PATH", "")
    monkeypatch.setenv("TETREFINE_SERVER", server_binary)
    assert tetrefine.find_server_binary() == server_binary
    # An explicit binary wins.
    assert tetrefine.find_server_binary(server_binary) == server_binary


@pytest.mark.parametrize("arguments, message", [
    (dict(flags="--threads=1"), "flags: expected a sequence of strings"),
    (dict(flags=[3]), "flags: expected a sequence of strings"),
    (dict(start_timeout=0), "start_timeout: expected a positive number"),
])
def test_bad_arguments_are_refused(server_binary, arguments, message):
    with pytest.raises(tetrefine.TetrefineError) as refused:
        tetrefine.LocalServer(server_binary, **arguments)
    assert refused.value.code == grpc.StatusCode.INVALID_ARGUMENT
    assert message in refused.value.details


def test_numpy_results_survive_the_server(server_binary):
    # The arrays a result holds are the client's own: usable after the server has stopped.
    x, y, z = np.meshgrid(np.arange(16.0), np.arange(16.0), np.arange(8.0), indexing="ij")
    volume = np.sin(0.4 * x) * np.cos(0.3 * y) + 0.05 * z
    points = np.array([[1, 1, 1], [14, 1, 1], [1, 14, 1], [1, 1, 6]], dtype=float)
    with tetrefine.LocalServer(server_binary) as server, server.client() as client:
        result = client.refine(volume, (1, 1, 1), (0, 0, 0), points, np.array([[0, 1, 2, 3]]),
                               epsilon=0.05)
    assert result.tets.shape[1] == 4 and len(result.tets) > 1
    assert result.points.shape == (len(result.values), 3)


def test_closing_with_a_call_in_flight_ends_it_promptly(server_binary):
    # The pipeline is done (or interrupted) while its server still refines: close() cancels
    # the call after the 2 s drain instead of the server's default 30 s.
    volume, points, tets = _heavy_input()
    server = tetrefine.LocalServer(server_binary)
    client = server.client()
    started, outcome = threading.Event(), []

    def call():
        try:
            client.refine(volume, (1, 1, 1), (0, 0, 0), points, tets, 0.001, max_iterations=30,
                          on_iteration=lambda s: started.set())
            outcome.append("finished")
        except tetrefine.TetrefineError as error:
            outcome.append(error.code)

    worker = threading.Thread(target=call)
    worker.start()
    assert started.wait(60)
    begun = time.monotonic()
    server.close()
    closed = time.monotonic() - begun
    worker.join(60)
    client.close()
    assert not server.running
    assert closed < 15, closed
    assert outcome and outcome[0] != "finished", outcome
