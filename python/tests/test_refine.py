"""tetrefine.Client against a real tetrefine_server: the CLI's result, cancellation, errors."""

import json
import os
import signal
import subprocess
import threading
import time

import grpc
import meshio
import nibabel
import numpy as np
import pytest

import tetrefine
from conftest import EXAMPLE_MESH, EXAMPLE_VOLUME, Server
from meshes import box_mesh, noise_volume, smooth_volume


def run_cli(cli, *args):
    done = subprocess.run([cli, *args], capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    return done


def assert_same_as_cli_output(result, path):
    """result equals the CLI's output mesh file bit for bit (the .vtu stores float64 binary)."""
    cli = meshio.read(path)
    np.testing.assert_array_equal(result.points, cli.points)
    np.testing.assert_array_equal(result.tets, cli.cells_dict["tetra"])
    np.testing.assert_array_equal(result.values, cli.point_data["value"])
    np.testing.assert_array_equal(result.iteration, cli.cell_data["iteration"][0])
    np.testing.assert_array_equal(result.quality, cli.cell_data["quality"][0])


def test_the_example_matches_the_cli(server, cli_binary, tmp_path):
    output, stats = tmp_path / "cli.vtu", tmp_path / "cli.json"
    run_cli(cli_binary, "refine", "--server", server.target, "--volume", EXAMPLE_VOLUME,
            "--mesh", EXAMPLE_MESH, "--fit-mesh-to-volume", "--epsilon", "0.1", "--quiet",
            "--output", str(output), "--stats-json", str(stats))

    volume = tetrefine.volume_from_nibabel(nibabel.load(EXAMPLE_VOLUME))
    mesh = tetrefine.mesh_from_meshio(meshio.read(EXAMPLE_MESH))
    points = tetrefine.fit_to_volume(mesh.points, volume)
    seen = []
    with tetrefine.Client(server.target) as client:
        result = client.refine(volume.data, volume.spacing, volume.origin, points, mesh.tets,
                               0.1, on_iteration=seen.append)

    assert_same_as_cli_output(result, output)
    cli_stats = json.load(open(stats))
    assert result.stop_reason == cli_stats["stop_reason"]
    assert [s.iteration for s in result.iterations] == list(
        range(1, len(cli_stats["iterations"]) + 1))
    assert [s.final_tets for s in result.iterations] == [
        s["final_tets"] for s in cli_stats["iterations"]]
    assert seen == result.iterations
    assert result.lattice.points_sampled > 0
    assert len(result.tets) > len(mesh.tets)


def test_a_numpy_mesh_in_a_float_volume_matches_the_cli(server, cli_binary, tmp_path):
    """Arrays the caller made: written to files for the CLI, sent as arrays by the client."""
    data = smooth_volume((17, 13, 11)).astype(np.float32)
    spacing, origin = (1.5, 2.0, 0.75), (-10.0, 4.0, 2.5)
    image = nibabel.Nifti1Image(data, np.diag([*spacing, 1.0]))
    image.affine[:3, 3] = origin
    image = nibabel.Nifti1Image(data, image.affine)
    nibabel.save(image, tmp_path / "v.nii")
    hi = np.asarray(origin) + (np.asarray(data.shape) - 1) * np.asarray(spacing)
    points, tets = box_mesh(np.asarray(origin) + 0.5, hi - 0.5, (3, 4, 2))
    meshio.write(tmp_path / "m.vtu", meshio.Mesh(points, [("tetra", tets)]))
    run_cli(cli_binary, "refine", "--server", server.target, "--volume", str(tmp_path / "v.nii"),
            "--mesh", str(tmp_path / "m.vtu"), "--epsilon", "0.02", "--max-iterations", "5",
            "--quiet", "--output", str(tmp_path / "cli.vtu"))

    with tetrefine.Client(server.target) as client:
        result = client.refine(data, spacing, origin, points, tets, 0.02, max_iterations=5)
    assert_same_as_cli_output(result, tmp_path / "cli.vtu")


@pytest.mark.parametrize("scheme", ["paper", "longest-edge"])
def test_each_scheme_matches_the_cli(server, cli_binary, tmp_path, scheme):
    """scheme= sends the scheme the CLI's --scheme names: the same mesh, bit for bit."""
    data = smooth_volume((13, 11, 9))
    points, tets = box_mesh((0.5, 0.5, 0.5), (11.5, 9.5, 7.5), (3, 3, 2))
    nibabel.save(nibabel.Nifti1Image(data, np.eye(4)), tmp_path / "v.nii")
    meshio.write(tmp_path / "m.vtu", meshio.Mesh(points, [("tetra", tets)]))
    run_cli(cli_binary, "refine", "--server", server.target, "--volume", str(tmp_path / "v.nii"),
            "--mesh", str(tmp_path / "m.vtu"), "--epsilon", "0.02", "--scheme", scheme,
            "--quiet", "--output", str(tmp_path / "cli.vtu"))
    with tetrefine.Client(server.target) as client:
        result = client.refine(data, (1, 1, 1), (0, 0, 0), points, tets, 0.02, scheme=scheme)
    assert_same_as_cli_output(result, tmp_path / "cli.vtu")


def test_quality_reference_matches_the_cli(server, cli_binary, tmp_path):
    """quality_reference= sends what the CLI's --quality-reference sends: the same mesh, bit for
    bit; out of (0, 1] the server refuses it by name."""
    data = smooth_volume((13, 11, 9))
    points, tets = box_mesh((0.5, 0.5, 0.5), (11.5, 9.5, 7.5), (3, 3, 2))
    nibabel.save(nibabel.Nifti1Image(data, np.eye(4)), tmp_path / "v.nii")
    meshio.write(tmp_path / "m.vtu", meshio.Mesh(points, [("tetra", tets)]))
    run_cli(cli_binary, "refine", "--server", server.target, "--volume", str(tmp_path / "v.nii"),
            "--mesh", str(tmp_path / "m.vtu"), "--epsilon", "0.02", "--quality-reference", "0.9",
            "--quiet", "--output", str(tmp_path / "cli.vtu"))
    with tetrefine.Client(server.target) as client:
        result = client.refine(data, (1, 1, 1), (0, 0, 0), points, tets, 0.02,
                               quality_reference=0.9)
        assert_same_as_cli_output(result, tmp_path / "cli.vtu")
        with pytest.raises(tetrefine.TetrefineError) as error:
            client.refine(data, (1, 1, 1), (0, 0, 0), points, tets, 0.02, quality_reference=1.5)
    assert error.value.code == grpc.StatusCode.INVALID_ARGUMENT
    assert "quality_reference" in error.value.details


def test_certify_labels_and_parents(server):
    """certify=True bounds the lattice error of every tet; labels and parents follow each child
    (every region and every input tet keeps its volume)."""
    data = smooth_volume((13, 11, 9))
    points, tets = box_mesh((0.5, 0.5, 0.5), (11.5, 9.5, 7.5), (3, 3, 2))
    labels = np.arange(len(tets)) % 3 + 10
    with tetrefine.Client(server.target) as client:
        result = client.refine(data, (1, 1, 1), (0, 0, 0), points, tets, 0.05, certify=True,
                               labels=labels, track_parents=True)
    assert result.stop_reason == "converged"
    assert result.certified_max_error is not None and result.certified_max_error <= 0.05
    assert len(result.parent) == len(result.tets) == len(result.labels)
    np.testing.assert_array_equal(result.labels, labels[result.parent])

    def volumes(p, t):
        a, b, c, d = (p[t[:, k]] for k in range(4))
        return np.einsum("ij,ij->i", b - a, np.cross(c - a, d - a)) / 6.0

    before, after = volumes(points, tets), volumes(result.points, result.tets)
    assert (after > 0).all()
    np.testing.assert_allclose(np.bincount(result.parent, weights=after, minlength=len(tets)),
                               before, rtol=1e-9)
    with tetrefine.Client(server.target) as client:
        plain = client.refine(data, (1, 1, 1), (0, 0, 0), points, tets, 0.05)
    assert plain.certified_max_error is None and plain.parent is None


def test_on_mesh_streams_every_iterations_mesh(server):
    """on_mesh gets each iteration's mesh after its statistics: as many tets as they say, the
    input's volume and each region's, labels following the tets, and the last one equal to the
    result."""
    data = smooth_volume((13, 11, 9))
    points, tets = box_mesh((0.5, 0.5, 0.5), (11.5, 9.5, 7.5), (3, 3, 2))
    labels = np.arange(len(tets)) % 2 + 4
    events = []

    def volumes(p, t):
        a, b, c, d = (p[t[:, k]] for k in range(4))
        return np.einsum("ij,ij->i", b - a, np.cross(c - a, d - a)) / 6.0

    region_volumes = np.bincount(labels, weights=volumes(points, tets))
    with tetrefine.Client(server.target) as client:
        result = client.refine(data, (1, 1, 1), (0, 0, 0), points, tets, 0.02, labels=labels,
                               on_iteration=lambda stats: events.append(stats),
                               on_mesh=lambda mesh: events.append(mesh))
        plain = client.refine(data, (1, 1, 1), (0, 0, 0), points, tets, 0.02, labels=labels)
    assert len(result.iterations) >= 2
    assert len(events) == 2 * len(result.iterations)
    for k, stats in enumerate(result.iterations):
        assert events[2 * k] is stats
        mesh = events[2 * k + 1]
        assert isinstance(mesh, tetrefine.IterationMesh)
        assert mesh.iteration == stats.iteration == k + 1
        assert len(mesh.tets) == stats.final_tets
        assert mesh.tets.dtype == np.int64 and mesh.tets.shape[1] == 4
        assert len(mesh.values) == len(mesh.points) and len(mesh.labels) == len(mesh.tets)
        v = volumes(mesh.points, mesh.tets)
        assert (v > 0).all()
        np.testing.assert_allclose(np.bincount(mesh.labels, weights=v), region_volumes,
                                   rtol=1e-12)
    last = events[-1]
    np.testing.assert_array_equal(last.points, result.points)
    np.testing.assert_array_equal(last.tets, result.tets)
    np.testing.assert_array_equal(last.values, result.values)
    np.testing.assert_array_equal(last.labels, result.labels)
    # Streaming changes nothing in the result.
    np.testing.assert_array_equal(plain.tets, result.tets)
    np.testing.assert_array_equal(plain.points, result.points)
    assert [s.as_dict() | {"seconds": 0} for s in plain.iterations] == \
        [s.as_dict() | {"seconds": 0} for s in result.iterations]


def test_volume_axes_are_x_y_z(server):
    """On a volume linear along one axis the vertex values are that coordinate: any axis or
    memory-order mix-up would give another axis's coordinate."""
    shape, spacing, origin = (9, 7, 5), (1.0, 2.0, 3.0), (10.0, 20.0, 30.0)
    index = np.meshgrid(*(np.arange(n, dtype=np.float64) for n in shape), indexing="ij")
    hi = np.asarray(origin) + (np.asarray(shape) - 1) * np.asarray(spacing)
    points, tets = box_mesh(origin, hi, (2, 2, 2))
    with tetrefine.Client(server.target) as client:
        for axis in range(3):
            world = origin[axis] + spacing[axis] * index[axis]
            for layout in (world, np.asfortranarray(world), world.copy(order="C")):
                result = client.refine(layout, spacing, origin, points, tets, 0.5,
                                       max_iterations=0)
                np.testing.assert_allclose(result.values, result.points[:, axis], rtol=1e-12)


def _same(a, b):
    np.testing.assert_array_equal(a.points, b.points)
    np.testing.assert_array_equal(a.tets, b.tets)
    np.testing.assert_array_equal(a.values, b.values)


def test_every_dtype_and_layout_gives_the_result_of_its_values(server):
    """A sample's value, not its dtype or memory layout, decides the result."""
    base = np.random.default_rng(3).integers(0, 120, size=(12, 10, 8))
    points, tets = box_mesh((0.5, 0.5, 0.5), (10.5, 8.5, 6.5), (2, 2, 2))
    with tetrefine.Client(server.target) as client:
        def refine(volume):
            return client.refine(volume, (1, 1, 1), (0, 0, 0), points, tets, 0.05,
                                 max_iterations=3)
        reference = refine(base.astype(np.float64))
        assert len(reference.iterations) > 0
        for dtype in ("u1", "i1", "<i2", ">i2", "u2", "i4", ">i4", "u4", "i8", "u8", "f2",
                      "f4", ">f4", "f8", ">f8"):
            _same(refine(base.astype(dtype)), reference)
        bigger = np.zeros((24, 10, 16), dtype=np.int16)
        bigger[::2, :, ::2] = base
        _same(refine(bigger[::2, :, ::2]), reference)  # a strided view
        _same(refine(np.asfortranarray(base)), reference)
        _same(refine(base.T.copy().T), reference)  # C order of the reversed axes
        _same(refine(base.astype(np.int64) + 2**40 - 2**40), reference)
        huge = base.astype(np.int64) * 2**45
        result = refine(huge)  # travels as float64: exact below 2**53
        np.testing.assert_array_equal(result.points, reference.points)
        too_big = base.astype(np.uint64) * 2**56
        with pytest.raises(tetrefine.TetrefineError, match="volume: uint64 values"):
            refine(too_big)


def _heavy_input():
    """Noise on a 40^3 grid meshed at one tet per voxel-ish: every iteration splits a lot, so a
    cancelled call is still running when the cancellation arrives."""
    volume = noise_volume((40, 40, 40))
    points, tets = box_mesh((0, 0, 0), (39, 39, 39), (39, 39, 39))
    return volume, points, tets


class Stop(Exception):
    pass


@pytest.mark.parametrize("callback", ["on_iteration", "on_mesh"])
def test_a_callback_raising_cancels_the_call(own_server, callback):
    volume, points, tets = _heavy_input()
    calls = []

    def stop(stats_or_mesh):
        calls.append(stats_or_mesh.iteration)
        raise Stop()

    with tetrefine.Client(own_server.target) as client:
        with pytest.raises(Stop):
            client.refine(volume, (1, 1, 1), (0, 0, 0), points, tets, 0.01, max_iterations=16,
                          **{callback: stop})
        assert calls == [1]
        lines = own_server.wait_for_refine_lines(1)
        assert len(lines) == 1 and "status=CANCELLED" in lines[0], lines
        # The client and the server are fine afterwards.
        small = client.refine(smooth_volume((8, 8, 8)), (1, 1, 1), (0, 0, 0),
                              *box_mesh((1, 1, 1), (6, 6, 6), (1, 1, 1)), 0.1)
        assert len(small.tets) >= 5


class OtherServiceDown(grpc.RpcError):
    """What a callback that calls another gRPC service gets when that one is down."""


def test_a_callback_raising_an_rpc_error_gets_it_back_and_cancels_the_call(own_server):
    # It was taken for this call's own failure: a TetrefineError(UNAVAILABLE) as if the
    # tetrefine server were down, and the server refined on to the end.
    volume, points, tets = _heavy_input()
    raised = OtherServiceDown()

    def stop(stats):
        raise raised

    with tetrefine.Client(own_server.target) as client:
        with pytest.raises(OtherServiceDown) as error:
            client.refine(volume, (1, 1, 1), (0, 0, 0), points, tets, 0.01, max_iterations=16,
                          on_iteration=stop)
    assert error.value is raised
    lines = own_server.wait_for_refine_lines(1)
    assert len(lines) == 1 and "status=CANCELLED" in lines[0], lines


def test_a_frozen_server_ends_the_call_without_a_timeout(own_server, monkeypatch):
    # A server that stops answering mid-call (SIGSTOP here; a host gone without a reset alike)
    # left refine() without a timeout waiting forever. Keepalive pings (30 s, answered within
    # 20 s) end it with UNAVAILABLE, as for the CLI. Here at the fastest the server accepts (a
    # ping every 10 s, 3 s to answer): with the client's own values this test waited 50 s.
    monkeypatch.setattr(tetrefine.client, "_KEEPALIVE_TIME_MS", 10_000)
    monkeypatch.setattr(tetrefine.client, "_KEEPALIVE_TIMEOUT_MS", 3_000)
    volume, points, tets = _heavy_input()
    started = []
    with tetrefine.Client(own_server.target) as client:
        client.server_info()

        def freeze(stats):
            if not started:
                started.append(time.monotonic())
                own_server.process.send_signal(signal.SIGSTOP)

        # Without the pings the call would wait for ever: the server thaws after 100 s, and
        # the call then ends without the error this test expects, rather than hanging.
        thaw = threading.Timer(100, lambda: own_server.process.send_signal(signal.SIGCONT))
        thaw.start()
        try:
            with pytest.raises(tetrefine.TetrefineError) as error:
                client.refine(volume, (1, 1, 1), (0, 0, 0), points, tets, 0.01,
                              max_iterations=16, on_iteration=freeze)
        finally:
            thaw.cancel()
            own_server.process.send_signal(signal.SIGCONT)
    assert error.value.code == grpc.StatusCode.UNAVAILABLE, error.value
    assert started and time.monotonic() - started[0] < 40


def test_a_server_restarted_with_a_smaller_message_limit_is_asked_again(server_binary):
    # The client asks the limit once; every later call failed with "Received message larger
    # than max" after a restart with a smaller one (an outside review).
    import socket
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        port = probe.getsockname()[1]
    volume = noise_volume((40, 40, 40))
    points, tets = box_mesh((1, 1, 1), (38, 38, 38), (3, 3, 3))
    first = Server(server_binary, [f"--listen=127.0.0.1:{port}"]).start()
    try:
        client = tetrefine.Client(first.target)
        client.refine(volume, (1, 1, 1), (0, 0, 0), points, tets, 0.5, max_iterations=1)
    finally:
        first.stop()
    second = Server(server_binary, [f"--listen=127.0.0.1:{port}",
                                    "--max_message_bytes=65536"]).start()
    try:
        with pytest.raises(tetrefine.TetrefineError) as error:
            client.refine(volume, (1, 1, 1), (0, 0, 0), points, tets, 0.5, max_iterations=1)
        assert error.value.code == grpc.StatusCode.RESOURCE_EXHAUSTED
        assert "the next call asks again" in error.value.details
        result = client.refine(volume, (1, 1, 1), (0, 0, 0), points, tets, 0.5, max_iterations=1)
        assert len(result.tets) >= len(tets)
        client.close()
    finally:
        second.stop()


def test_a_deadline_ends_the_call_with_deadline_exceeded(own_server):
    volume, points, tets = _heavy_input()
    with tetrefine.Client(own_server.target) as client:
        client.server_info()  # connect first, so the deadline is spent on the call itself
        with pytest.raises(tetrefine.TetrefineError) as error:
            client.refine(volume, (1, 1, 1), (0, 0, 0), points, tets, 0.01, timeout=0.2)
    assert error.value.code == grpc.StatusCode.DEADLINE_EXCEEDED
    lines = own_server.wait_for_refine_lines(1)
    assert "status=OK" not in lines[0], lines


def test_the_servers_message_for_bad_input(server):
    volume = smooth_volume((8, 8, 8))
    points, tets = box_mesh((1, 1, 1), (6, 6, 6), (1, 1, 1))
    outside = points.copy()
    outside[3] = (1.0, 20.0, 1.0)
    with tetrefine.Client(server.target) as client:
        with pytest.raises(tetrefine.TetrefineError) as error:
            client.refine(volume, (1, 1, 1), (0, 0, 0), outside, tets, 0.1)
        assert error.value.code == grpc.StatusCode.INVALID_ARGUMENT
        assert "mesh.points[3]" in error.value.details and "outside" in error.value.details
        assert str(error.value).startswith("INVALID_ARGUMENT: mesh.points[3]")

        with pytest.raises(tetrefine.TetrefineError) as error:
            client.refine(volume, (1, 1, 1), (0, 0, 0), points, tets, 0.0)
        assert error.value.code == grpc.StatusCode.INVALID_ARGUMENT
        assert "epsilon" in error.value.details

        inverted = tets.copy()
        inverted[2] = inverted[2][[0, 1, 3, 2]]
        with pytest.raises(tetrefine.TetrefineError, match=r"tets\[2\]|tet 2"):
            client.refine(volume, (1, 1, 1), (0, 0, 0), points, inverted, 0.1)
        assert len(client.refine(volume, (1, 1, 1), (0, 0, 0), points, inverted, 0.1,
                                 fix_orientation=True).tets) >= 5


@pytest.mark.parametrize("arguments, message", [
    (dict(tets=np.array([[0, 1, 2, 99]])), "tets: tet 0 corner 3 is vertex 99"),
    (dict(tets=np.array([[0, 1, 2, -1]])), "tets: tet 0 corner 3 is vertex -1"),
    (dict(tets=np.zeros((2, 3), dtype=int)), r"tets: expected shape \(m, 4\)"),
    (dict(points=np.full((8, 3), np.nan)), "points: vertex 0 is not finite"),
    (dict(volume=np.zeros((8, 8))), r"volume: expected a 3-d array indexed \[x, y, z\]"),
    (dict(volume=np.zeros((8, 1, 8))), "volume: every axis needs at least 2 samples"),
    (dict(volume=np.zeros((8, 8, 8), dtype=complex)), "volume: dtype complex128"),
    (dict(spacing=(1, 0, 1)), "spacing: must be > 0 on every axis, got 0.0 on axis y"),
    (dict(origin=(0, 0)), "origin: expected 3 numbers, got 2"),
    (dict(direction=np.eye(2)), r"direction: expected a 3x3 matrix"),
    # Found by a review (2026-11-28): a direction with lengths scaled the volume a second time;
    # a complex one warned and then said "column 0 is zero".
    (dict(direction=np.diag([2.0, 2.0, 2.0])), "direction: column 0 has length 2; the columns "
     "are unit vectors"),
    (dict(direction=np.eye(3) * (1 + 0j)), "direction: expected real numbers"),
    # Found by a sweep of the API (2026-11-25): these raised numpy's, protobuf's or Python's own
    # exceptions, or were coerced.
    (dict(tets=[[0, 1, 2, 3], [0, 1, 2]]), "tets: not an array of numbers"),
    (dict(points=[[1, 1, 1], [2, 2]]), "points: not an array of numbers"),
    (dict(tets=np.array([[0, 1, 2, np.inf]])), "tets: tet 0 corner 3 is inf, not a vertex index"),
    (dict(tets=np.array([[0, 1, 2, 2.5]])), "tets: tet 0 corner 3 is 2.5"),
    (dict(epsilon="0.1"), "epsilon: expected a number, got '0.1'"),
    (dict(epsilon=True), "epsilon: expected a number"),
    (dict(epsilon=None), "epsilon: expected a number"),
    (dict(max_iterations=2.7), "max_iterations: expected a whole number, got 2.7"),
    (dict(max_iterations=2**40), r"max_iterations: must be in \[0, 2147483647\]"),
    (dict(max_tets=float("inf")), "max_tets: expected a whole number, got inf"),
    (dict(norm_coeff="x"), "norm_coeff: expected a number"),
    (dict(quality_reference="x"), "quality_reference: expected a number"),
    (dict(certify="no"), "certify: expected True or False, got 'no'"),
    (dict(timeout="5"), "timeout: expected a number"),
    (dict(timeout=-1), "timeout: must be >= 0"),
    (dict(timeout=float("nan")), "timeout: must be >= 0"),
    (dict(spacing=np.array([1, 1, 1j])), "spacing: expected 3 real numbers"),
    (dict(volume=np.full((4, 4, 4), np.longdouble(1) + np.longdouble(2)**-60)),
     "volume: float128 values would round in float64"),
    # An object where an array goes read as "got shape ()" (an outside review, 2026-11-28).
    (dict(volume=tetrefine.VolumeGrid(np.zeros((4, 4, 4)), [1, 1, 1], [0, 0, 0])),
     r"volume: expected an array of numbers, got a VolumeGrid \(pass grid.data"),
    (dict(volume=nibabel.Nifti1Image(np.zeros((4, 4, 4), np.float32), np.eye(4))),
     r"volume: expected an array of numbers, got a Nifti1Image \(volume_from_nibabel"),
    (dict(points=meshio.Mesh(np.zeros((4, 3)), [("tetra", np.array([[0, 1, 2, 3]]))])),
     r"points: expected an array of numbers, got a Mesh \(mesh_from_meshio"),
])
def test_input_refused_before_sending(server, arguments, message):
    points, tets = box_mesh((1, 1, 1), (6, 6, 6), (1, 1, 1))
    call = dict(volume=smooth_volume((8, 8, 8)), spacing=(1, 1, 1), origin=(0, 0, 0),
                points=points, tets=tets, epsilon=0.1)
    call.update(arguments)
    with tetrefine.Client(server.target) as client:
        with pytest.raises(tetrefine.TetrefineError, match=message) as error:
            client.refine(**call)
    assert error.value.code == grpc.StatusCode.INVALID_ARGUMENT


def test_an_infinite_timeout_is_no_limit(server):
    points, tets = box_mesh((1, 1, 1), (6, 6, 6), (1, 1, 1))
    with tetrefine.Client(server.target) as client:
        result = client.refine(smooth_volume((8, 8, 8)), (1, 1, 1), (0, 0, 0), points, tets, 0.1,
                               timeout=float("inf"))
        assert result.stop_reason == "converged"
        assert client.server_info(timeout=1e12).version


def test_client_misuse_is_a_tetrefine_error(server):
    with pytest.raises(tetrefine.TetrefineError, match="target: expected"):
        tetrefine.Client(None)
    with pytest.raises(tetrefine.TetrefineError, match="token: must be a string of printable"):
        tetrefine.Client(server.target, token="a\nb")
    # gRPC would connect to port 70000 - 65536 = 4464.
    for target, port in (("127.0.0.1:70000", "70000"), ("localhost:0", "0"),
                         ("dns:///refiner.local:123456", "123456"),
                         ("ipv4:10.0.0.1:1,10.0.0.2:99999", "99999"), ("[::1]:65536", "65536")):
        with pytest.raises(tetrefine.TetrefineError,
                           match=rf"target: port {port} of .* is out of range \(1-65535\)"):
            tetrefine.Client(target)
    for target in ("127.0.0.1:65535", "dns://8.8.8.8/refiner:443", "[::1]:1",
                   "unix:/tmp/socket:99999", "host:http"):
        tetrefine.Client(target).close()
    for target in ("127.0.0.1", "refiner.local", "::1", "[::1]", "host:", "dns:///refiner.local",
                   "ipv4:10.0.0.1:1,10.0.0.2"):
        with pytest.raises(tetrefine.TetrefineError, match=r"target: .* has no port: write"):
            tetrefine.Client(target)
    closed = tetrefine.Client(server.target)
    closed.close()
    with pytest.raises(tetrefine.TetrefineError) as error:
        closed.refine(smooth_volume((8, 8, 8)), (1, 1, 1), (0, 0, 0),
                      *box_mesh((1, 1, 1), (6, 6, 6), (1, 1, 1)), 0.1)
    assert error.value.code == grpc.StatusCode.FAILED_PRECONDITION


def test_nested_statistics_are_plain_records(server):
    points, tets = box_mesh((1, 1, 1), (6, 6, 6), (1, 1, 1))
    with tetrefine.Client(server.target) as client:
        stats = client.refine(smooth_volume((8, 8, 8)), (1, 1, 1), (0, 0, 0), points, tets,
                              0.05).iterations[0]
    assert type(stats.quality) is tetrefine.Record
    assert stats.quality.count == stats.final_tets


@pytest.mark.parametrize("readme", ["README.md", "python/README.md"])
def test_the_readme_example_prints_what_the_readme_says(server, readme):
    """Each README's Python block, run against the test server: its printed line is the comment
    under it (the main one had drifted from what the server gives; the package's used
    variables it never defined)."""
    import contextlib
    import io
    import re

    path = os.path.join(os.path.dirname(__file__), "..", "..", readme)
    if not os.path.exists(path):
        pytest.skip(f"{readme} is not beside this package (an installed copy)")
    text = open(path).read()
    section = text[text.index("## Python"):] if "## Python" in text else text
    block = section[section.index("```python") + len("```python"):]
    block = block[:block.index("```")]
    expected = re.search(r"^# (converged .*)$", block, re.M).group(1)
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        exec(block.replace("localhost:50051", server.target), {})
    printed = out.getvalue().strip().splitlines()[-1]
    # The main README's line ends with the lattice maximum, given to 4 digits and "...".
    prefix = expected.rstrip(".")
    assert printed.startswith(prefix), (printed, expected)


def test_no_server_is_unavailable():
    with tetrefine.Client("127.0.0.1:1") as client:
        with pytest.raises(tetrefine.TetrefineError) as error:
            client.refine(smooth_volume((8, 8, 8)), (1, 1, 1), (0, 0, 0),
                          *box_mesh((1, 1, 1), (6, 6, 6), (1, 1, 1)), 0.1, timeout=10)
    assert error.value.code == grpc.StatusCode.UNAVAILABLE


def test_chunks_follow_the_servers_message_limit(server_binary):
    """A server with a small message limit still gets every chunk under it."""
    from conftest import Server
    small = Server(server_binary, ["--max_message_bytes=65536"]).start()
    try:
        volume = noise_volume((40, 40, 40))  # 512 KB of float64: 16 chunks or more
        points, tets = box_mesh((1, 1, 1), (38, 38, 38), (12, 12, 12))
        with tetrefine.Client(small.target) as client:
            assert client.server_info().limits.max_message_bytes == 65536
            result = client.refine(volume, (1, 1, 1), (0, 0, 0), points, tets, 0.05,
                                   max_iterations=1)
            # A negative label takes 10 bytes on the wire: 8,640 of them are 86 KB, and label
            # chunks sized at 4 bytes a label were refused by this server.
            labels = np.where(np.arange(len(tets)) % 2 == 0, -1, -2**31)
            labelled = client.refine(volume, (1, 1, 1), (0, 0, 0), points, tets, 0.05,
                                     max_iterations=1, labels=labels)
        assert len(result.tets) > len(tets)
        assert set(labelled.labels.tolist()) == {-1, -2**31}
    finally:
        small.stop()


def test_a_callback_slower_than_the_servers_write_stall_is_told_so(server_binary):
    """The server cancels a call whose client reads nothing for --write_stall_seconds; a
    cancel carries no message, so the client says what a callback's author needs to know."""
    from conftest import Server
    strict = Server(server_binary, ["--write_stall_seconds=1"]).start()
    try:
        volume = noise_volume((40, 40, 40))
        points, tets = box_mesh((1, 1, 1), (38, 38, 38), (12, 12, 12))

        def slow(stats):
            if stats.iteration == 1:
                time.sleep(4)  # the final mesh (megabytes) waits behind it

        with tetrefine.Client(strict.target) as client:
            with pytest.raises(tetrefine.TetrefineError) as error:
                client.refine(volume, (1, 1, 1), (0, 0, 0), points, tets, 0.02,
                              max_iterations=2, on_iteration=slow)
        assert error.value.code == grpc.StatusCode.CANCELLED
        assert "reads no response for 1 s (limits.write_stall_seconds)" in error.value.details
        assert "keep on_iteration and on_mesh short" in error.value.details
    finally:
        strict.stop()


def test_tls_with_a_client_certificate(server_binary, tmp_path):
    def openssl(*args):
        subprocess.run(["openssl", *args], check=True, capture_output=True)

    def key_and_cert(name, ca=None, extension=""):
        key, cert = tmp_path / f"{name}.key", tmp_path / f"{name}.pem"
        if ca is None:
            openssl("req", "-x509", "-newkey", "rsa:2048", "-nodes", "-days", "2", "-subj",
                    f"/CN={name}", "-keyout", str(key), "-out", str(cert))
        else:
            csr, ext = tmp_path / f"{name}.csr", tmp_path / f"{name}.ext"
            ext.write_text(extension)
            openssl("req", "-newkey", "rsa:2048", "-nodes", "-subj", f"/CN={name}", "-keyout",
                    str(key), "-out", str(csr))
            openssl("x509", "-req", "-in", str(csr), "-CA", str(ca[1]), "-CAkey", str(ca[0]),
                    "-CAcreateserial", "-days", "2", "-extfile", str(ext), "-out", str(cert))
        return key, cert

    ca = key_and_cert("ca")
    server_key = key_and_cert("server", ca, "subjectAltName=DNS:localhost,IP:127.0.0.1\n"
                              "extendedKeyUsage=serverAuth\n")
    client_key = key_and_cert("client", ca, "extendedKeyUsage=clientAuth\n")
    from conftest import Server
    tls_server = Server(server_binary, [f"--tls_cert={server_key[1]}",
                                        f"--tls_key={server_key[0]}",
                                        f"--tls_client_ca={ca[1]}"]).start()
    try:
        volume = smooth_volume((8, 8, 8))
        points, tets = box_mesh((1, 1, 1), (6, 6, 6), (1, 1, 1))
        tls = {"ca": ca[1], "cert": client_key[1], "key": client_key[0]}
        with tetrefine.Client(tls_server.target, tls=tls, token="not-checked-yet") as client:
            assert len(client.refine(volume, (1, 1, 1), (0, 0, 0), points, tets, 0.1).tets) >= 5
        with tetrefine.Client(tls_server.target, tls={"ca": ca[1]}) as client:
            with pytest.raises(tetrefine.TetrefineError) as error:
                client.refine(volume, (1, 1, 1), (0, 0, 0), points, tets, 0.1, timeout=10)
            assert error.value.code == grpc.StatusCode.UNAVAILABLE
    finally:
        tls_server.stop()
    with pytest.raises(tetrefine.TetrefineError, match="tls\\['ca'\\]: .*missing.pem"):
        tetrefine.Client("127.0.0.1:1", tls={"ca": tmp_path / "missing.pem"})
    # Not PEM: named at once (gRPC said "UNAVAILABLE: empty address list" when connecting).
    with pytest.raises(tetrefine.TetrefineError,
                       match="tls\\['ca'\\]: 7 bytes: not PEM") as error:
        tetrefine.Client("127.0.0.1:1", tls={"ca": b"garbage"})
    assert error.value.code == grpc.StatusCode.INVALID_ARGUMENT
    (tmp_path / "notakey.pem").write_bytes(b"not a key")
    with pytest.raises(tetrefine.TetrefineError, match="tls\\['key'\\]: .*notakey.pem: not PEM"):
        tetrefine.Client("127.0.0.1:1", tls={"ca": ca[1], "cert": client_key[1],
                                             "key": tmp_path / "notakey.pem"})
    # PEM, but the wrong PEM: named before connecting, as the CLI names them (gRPC said
    # "UNAVAILABLE: empty address list").
    for tls, message in [
            ({"cert": client_key[0], "key": client_key[1]},
             r"tls\['cert'\]: .*client.key holds no PEM certificate"),
            ({"cert": client_key[1], "key": server_key[0]},
             r"tls\['key'\]: .*server.key is not the private key of the tls\['cert'\] "
             r"certificate in .*client.pem"),
            ({"cert": client_key[1], "key": ca[1]},
             r"tls\['key'\]: .*ca.pem holds no unencrypted PEM private key"),
            ({"ca": ca[0]}, r"tls\['ca'\]: .*ca.key holds no PEM certificate"),
            ({"ca": ca[0].read_bytes()}, r"tls\['ca'\]: \d+ bytes holds no PEM certificate"),
            ({"cert": client_key[1].read_bytes(), "key": server_key[0].read_bytes()},
             r"tls\['key'\]: \d+ bytes is not the private key of the tls\['cert'\] "
             r"certificate in \d+ bytes")]:
        with pytest.raises(tetrefine.TetrefineError, match=message) as error:
            tetrefine.Client("127.0.0.1:1", tls=tls)
        assert error.value.code == grpc.StatusCode.INVALID_ARGUMENT

@pytest.mark.parametrize("callback", ["on_iteration", "on_mesh"])
def test_a_non_callable_callback_is_refused_before_sending(server, callback):
    points, tets = box_mesh((1, 1, 1), (5, 5, 5), (1, 1, 1))
    volume = np.zeros((8, 8, 8))
    with tetrefine.Client(server.target) as client:
        with pytest.raises(tetrefine.TetrefineError,
                           match=f"{callback}: expected a callable .* got int") as caught:
            client.refine(volume, (1, 1, 1), (0, 0, 0), points, tets, 0.1, **{callback: 5})
    assert caught.value.code == grpc.StatusCode.INVALID_ARGUMENT


def test_lattice_and_guard_options(server, cli_binary, tmp_path):
    # The CLI's --lattice-n and --lattice-max-tets, and the wire's lattice_seed, min_edge_length
    # and min_quality, could not be given from Python (a service sweep).
    output, stats = tmp_path / "cli.vtu", tmp_path / "cli.json"
    run_cli(cli_binary, "refine", "--server", server.target, "--volume", EXAMPLE_VOLUME,
            "--mesh", EXAMPLE_MESH, "--fit-mesh-to-volume", "--epsilon", "0.1", "--quiet",
            "--lattice-n", "5", "--lattice-max-tets", "300", "--max-iterations", "4",
            "--output", str(output), "--stats-json", str(stats))
    volume = tetrefine.volume_from_nibabel(nibabel.load(EXAMPLE_VOLUME))
    mesh = tetrefine.mesh_from_meshio(meshio.read(EXAMPLE_MESH))
    points = tetrefine.fit_to_volume(mesh.points, volume)
    args = (volume.data, volume.spacing, volume.origin, points, mesh.tets, 0.1)
    with tetrefine.Client(server.target) as client:
        result = client.refine(*args, lattice_n=5, lattice_max_tets=300, max_iterations=4)
        reseeded = client.refine(*args, lattice_n=5, lattice_max_tets=300, lattice_seed=7,
                                 max_iterations=4)
        guarded = client.refine(*args, min_edge_length=8.0, max_iterations=4)
        floored = client.refine(*args, min_quality=0.9, max_iterations=4)
        unchecked = client.refine(*args, lattice_n=0, max_iterations=4)
        with pytest.raises(tetrefine.TetrefineError) as error:
            client.refine(*args, lattice_n=-1)
    assert "lattice_n: must be in [0, 64]" in error.value.details
    # No check ran: the summary says order 0 (it said 8, with a max of 0).
    assert unchecked.lattice.n == 0 and unchecked.lattice.tets_sampled == 0
    assert_same_as_cli_output(result, output)
    cli_lattice = json.load(open(stats))["lattice"]
    assert result.lattice.n == 5 == cli_lattice["n"]
    assert result.lattice.tets_sampled == 300 == cli_lattice["tets_sampled"]
    assert result.lattice.max_error == cli_lattice["max_error"]
    # Another seed samples other tets of the same mesh.
    np.testing.assert_array_equal(reseeded.tets, result.tets)
    assert reseeded.lattice.tets_sampled == 300
    assert reseeded.lattice.mean_error != result.lattice.mean_error
    # The edge-length guard keeps edges below 8 mm whole: fewer tets than without it; a
    # quality floor of 0.9 refuses the first iteration.
    assert len(guarded.tets) < len(result.tets)
    assert floored.stop_reason == "quality_floor" and len(floored.tets) == len(mesh.tets)

    # The CLI has the same options: a run with all of them equals Python's.
    guarded_cli = tmp_path / "guarded.vtu"
    run_cli(cli_binary, "refine", "--server", server.target, "--volume", EXAMPLE_VOLUME,
            "--mesh", EXAMPLE_MESH, "--fit-mesh-to-volume", "--epsilon", "0.1", "--quiet",
            "--lattice-n", "5", "--lattice-max-tets", "300", "--lattice-seed", "7",
            "--min-edge-length", "8", "--min-quality", "0.001", "--max-iterations", "4",
            "--output", str(guarded_cli))
    with tetrefine.Client(server.target) as client:
        same = client.refine(*args, lattice_n=5, lattice_max_tets=300, lattice_seed=7,
                             min_edge_length=8.0, min_quality=0.001, max_iterations=4)
    assert_same_as_cli_output(same, guarded_cli)
    refused = subprocess.run([cli_binary, "refine", "--volume", EXAMPLE_VOLUME, "--mesh",
                              EXAMPLE_MESH, "--fit-mesh-to-volume", "--epsilon", "0.1",
                              "--min-quality", "2", "--output", str(tmp_path / "x.vtu")],
                             capture_output=True, text=True, timeout=60)
    assert refused.returncode == 2 and "--min-quality" in refused.stderr, refused.stderr
