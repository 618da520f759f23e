#!/usr/bin/env python3
"""Refines a small analytic volume and mesh on a tetrefine server and prints the statistics.

The stubs are generated at build time into <build>/python (target tetrefine_proto_python):

    PYTHONPATH=build/python python3 examples/python/refine_example.py --target localhost:50051

Exits non-zero when the call fails or the answer is inconsistent.
"""

import argparse
import sys

import grpc
import numpy as np

from tetrefine.v1 import tetrefine_pb2 as pb
from tetrefine.v1 import tetrefine_pb2_grpc as pb_grpc

CHUNK_BYTES = 1 << 20  # well under gRPC's 4 MiB message limit


def analytic_volume(dims):
    """float32 samples of a smooth field, shape (z, y, x): x varies fastest in memory."""
    z, y, x = np.meshgrid(*(np.arange(n, dtype=np.float64) for n in dims[::-1]), indexing="ij")
    field = np.sin(0.45 * x) * np.cos(0.35 * y) + 0.02 * z * z + 0.3 * np.sin(0.8 * y + 0.6 * z)
    return field.astype("<f4")


def five_tet_mesh(lo, hi, cells):
    """The box [lo, hi] as `cells` cells per axis, 5 positively oriented tets per cell."""
    axes = [np.linspace(lo[a], hi[a], cells[a] + 1) for a in range(3)]
    zz, yy, xx = np.meshgrid(axes[2], axes[1], axes[0], indexing="ij")
    points = np.stack([xx.ravel(), yy.ravel(), zz.ravel()], axis=1)
    nx, ny = cells[0] + 1, cells[1] + 1

    tets = []
    for k in range(cells[2]):
        for j in range(cells[1]):
            for i in range(cells[0]):
                c = [(i + (b & 1)) + nx * ((j + ((b >> 1) & 1)) + ny * (k + (b >> 2)))
                     for b in range(8)]
                # Alternating cell parity makes the face diagonals of neighbours coincide.
                even = (i + j + k) % 2 == 0
                corners = (0, 3, 5, 6) if even else (1, 2, 4, 7)
                center = (1, 2, 4, 7) if even else (0, 3, 5, 6)
                for corner in corners:
                    tets.append([c[corner], c[corner ^ 1], c[corner ^ 2], c[corner ^ 4]])
                tets.append([c[v] for v in center])
    tets = np.array(tets, dtype=np.uint32)

    p = points[tets]
    volume6 = np.einsum("ij,ij->i", p[:, 1] - p[:, 0],
                        np.cross(p[:, 2] - p[:, 0], p[:, 3] - p[:, 0]))
    inverted = volume6 < 0
    tets[inverted] = tets[inverted][:, [0, 1, 3, 2]]
    return points, tets


def requests(volume, points, tets, epsilon):
    """The Refine request stream: options, volume, mesh, end of input."""
    yield pb.RefineRequest(options=pb.RefineOptions(
        epsilon=epsilon, max_iterations=8, lattice_n=8))

    nz, ny, nx = volume.shape
    data = volume.tobytes()
    yield pb.RefineRequest(volume_header=pb.VolumeHeader(
        dims=pb.GridIndex(x=nx, y=ny, z=nz),
        origin=pb.Vector3(x=0.0, y=0.0, z=0.0),
        spacing=pb.Vector3(x=1.0, y=1.0, z=1.0),
        voxel_type=pb.VOXEL_TYPE_FLOAT32,
        total_bytes=len(data)))
    for offset in range(0, len(data), CHUNK_BYTES):
        yield pb.RefineRequest(volume_chunk=pb.VolumeChunk(
            offset=offset, data=data[offset:offset + CHUNK_BYTES]))

    yield pb.RefineRequest(mesh_header=pb.MeshHeader(
        vertex_count=len(points), tet_count=len(tets)))
    per_chunk = CHUNK_BYTES // 24
    for start in range(0, len(points), per_chunk):
        yield pb.RefineRequest(vertex_chunk=pb.VertexChunk(
            start_index=start, coordinates=points[start:start + per_chunk].ravel().tolist()))
    per_chunk = CHUNK_BYTES // 16
    for start in range(0, len(tets), per_chunk):
        yield pb.RefineRequest(tet_chunk=pb.TetChunk(
            start_index=start, indices=tets[start:start + per_chunk].ravel().tolist()))
    yield pb.RefineRequest(end_of_input=pb.EndOfInput())


def refine(stub, volume, points, tets, epsilon, timeout):
    """Runs the call; returns (iteration stats, final mesh arrays, summary)."""
    stats, summary = [], None
    header, parts = None, {}
    for response in stub.Refine(requests(volume, points, tets, epsilon), timeout=timeout):
        kind = response.WhichOneof("kind")
        if kind == "iteration_stats":
            s = response.iteration_stats
            stats.append(s)
            print(f"iteration {s.iteration}: {s.initial_tets} -> {s.final_tets} tets, "
                  f"{s.split_edges}/{s.edges} edges split, max error {s.max_error:.4g}, "
                  f"quality min {s.quality.min:.3f} mean {s.quality.mean:.3f}, "
                  f"{s.seconds * 1e3:.1f} ms")
        elif kind == "mesh_header":
            header = response.mesh_header
            parts = {"vertex_chunk": [], "value_chunk": [], "tet_chunk": [],
                     "tet_iteration_chunk": [], "tet_quality_chunk": []}
        elif kind == "summary":
            summary = response.summary
        else:
            chunk = getattr(response, kind)
            field = {"vertex_chunk": "coordinates", "value_chunk": "values",
                     "tet_chunk": "indices", "tet_iteration_chunk": "iterations",
                     "tet_quality_chunk": "qualities"}[kind]
            parts[kind].extend(getattr(chunk, field))
    mesh = {
        "points": np.array(parts["vertex_chunk"], dtype=np.float64).reshape(-1, 3),
        "values": np.array(parts["value_chunk"], dtype=np.float64),
        "tets": np.array(parts["tet_chunk"], dtype=np.uint32).reshape(-1, 4),
        "tet_iteration": np.array(parts["tet_iteration_chunk"], dtype=np.int32),
        "tet_quality": np.array(parts["tet_quality_chunk"], dtype=np.float32),
    }
    return stats, header, mesh, summary


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--target", default="localhost:50051", help="server host:port")
    parser.add_argument("--epsilon", type=float, default=0.02)
    parser.add_argument("--cells", type=int, default=4, help="mesh cells per axis")
    parser.add_argument("--timeout", type=float, default=60.0, help="call deadline, seconds")
    args = parser.parse_args()

    with grpc.insecure_channel(args.target) as channel:
        stub = pb_grpc.RefinerStub(channel)
        info = stub.GetServerInfo(pb.GetServerInfoRequest(), timeout=10, wait_for_ready=True)
        print(f"server {info.version}: max {info.limits.max_voxels} voxels, "
              f"{info.limits.max_input_tets} input tets, {info.limits.max_output_tets} output tets")

        volume = analytic_volume((16, 16, 16))
        points, tets = five_tet_mesh((1.0, 1.0, 1.0), (14.0, 14.0, 14.0), (args.cells,) * 3)
        print(f"input: {volume.shape[::-1]} float32 volume, {len(points)} vertices, "
              f"{len(tets)} tets")
        try:
            stats, header, mesh, summary = refine(stub, volume, points, tets, args.epsilon,
                                                  args.timeout)
        except grpc.RpcError as error:
            print(f"Refine failed: {error.code().name}: {error.details()}", file=sys.stderr)
            return 1

    problems = []
    if summary is None:
        problems.append("no summary")
    elif header is None or not header.final:
        problems.append("no final mesh")
    else:
        if len(mesh["tets"]) != summary.output_tets or len(mesh["tets"]) != header.tet_count:
            problems.append("tet count differs from the summary")
        if len(mesh["points"]) != summary.output_vertices or len(mesh["values"]) != len(
                mesh["points"]):
            problems.append("vertex or value count differs from the summary")
        if len(mesh["tet_quality"]) != len(mesh["tets"]):
            problems.append("tet_quality is not per tet")
        if len(stats) != summary.iterations:
            problems.append("iteration_stats count differs from the summary")
        if mesh["tets"].size and mesh["tets"].max() >= len(mesh["points"]):
            problems.append("tet index out of range")
    if problems:
        print("inconsistent answer: " + "; ".join(problems), file=sys.stderr)
        return 1

    print(f"stopped: {pb.StopReason.Name(summary.stop_reason)} after {summary.iterations} "
          f"iterations; {summary.input_tets} -> {summary.output_tets} tets; "
          f"quality min {summary.final_quality.min:.3f}; lattice max error "
          f"{summary.lattice.max_error:.4g} over {summary.lattice.points_sampled} points; "
          f"server {summary.total_seconds * 1e3:.1f} ms")
    return 0


if __name__ == "__main__":
    sys.exit(main())
