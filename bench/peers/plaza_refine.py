#!/usr/bin/python3
"""Plaza refinement (DOLFINx) driven by tetrefine's edge-midpoint marks: the peer baseline of the
paper reproduction (tools/reproduce).

Each round samples the volume at every vertex, computes every edge's midpoint error
|trilinear(midpoint) - (v_a + v_b) / 2| / normCoeff exactly as core/refine.cc does, marks the edges
above epsilon and hands them to dolfinx.mesh.refine, which is Plaza and Carey's skeleton-based
refinement in DOLFINx 0.5 (dolfinx::refinement::plaza::refine): it also splits the longest edge of
every face with a marked edge, to a fixpoint, so the mesh stays conformal with bounded quality.
Rounds go on until no edge is marked (converged), for at most --max-rounds rounds (max_rounds), or
until a round would exceed --max-tets tets (tet_budget: that round is discarded, as core refuses
such an iteration).

The result is scored as tools/reproduce scores tetrefine: the edge-midpoint error of the result,
the discrepancy on the paper's 165-point barycentric lattice (n = 8, every tet; core/lattice.cc),
mean-ratio quality (core/quality.cc). Trilinear sampling repeats core/volume.cc operation by
operation in float64 (continuous index (p - origin) / spacing, clamped to the grid's box, the cell
clamped to the last one, lerps along x, then y, then z): numpy does not fuse multiply-adds, so the
values are the same bits as core's.

Input: a case directory as tetrefine_reproduce --peer_dir writes it:
  volume.npy  float64, shape (nz, ny, nx): the samples, x fastest (the Volume's own layout; the
              reproduction's volumes are axis-aligned in tetrefine's world frame)
  case.json   {"origin": [x, y, z], "spacing": [x, y, z], "norm_coeff": max - min} and, for an
              oblique grid, "world_to_index": 9 values, row-major (core's
              Volume::world_to_index(): continuous index = M (p - origin), summed left to right)
  mesh.vtu    the input tets in world coordinates (as tetrefine writes .vtu: inline binary or ascii
              arrays, uncompressed)
Output (--output, else stdout): one JSON object, see plaza_refine() and score_mesh(); with
--mesh-out FILE.vtu also the final mesh, positively oriented, with its sampled "value" per vertex,
in the .vtu layout tetrefine writes, so that `tetrefine verify` and the reproduction read it.

Run with Debian's interpreter (/usr/bin/python3): python3-dolfinx is installed for it
(bench/peers/install-peers.sh). The numerics (load_case, sample, score_mesh, ...) need numpy only.
"""

import argparse
import base64
import json
import os
import sys
import time
import xml.etree.ElementTree as ET

try:
    import numpy as np
except ImportError:  # python3-dolfinx needs numpy: without it there is no peer to run (main says so)
    np = None

# Statuses of the refinement loop, named like core's StopReason where they mean the same.
CONVERGED = "converged"
MAX_ROUNDS = "max_rounds"
TET_BUDGET = "tet_budget"

# Exit status when python3-dolfinx (or numpy) does not import (tools/reproduce/plaza_peer.cc
# knows it).
EXIT_DOLFINX_MISSING = 3

LATTICE_N = 8
# Tets per block of the lattice pass: 8192 tets x 165 points keeps every temporary near 30 MB.
LATTICE_CHUNK = 8192


class CaseError(Exception):
    """An input file that cannot be used; the message names the file."""


class Case:
    """A volume on a grid (axis-aligned, or oblique with world_to_index) and a tet mesh in it."""

    def __init__(self, volume, origin, spacing, norm_coeff, points, tets, world_to_index=None):
        self.volume = np.ascontiguousarray(volume, dtype=np.float64)  # (nz, ny, nx)
        self.origin = np.asarray(origin, dtype=np.float64)  # (3,)
        self.spacing = np.asarray(spacing, dtype=np.float64)  # (3,)
        self.norm_coeff = float(norm_coeff)
        self.points = np.ascontiguousarray(points, dtype=np.float64)  # (V, 3)
        self.tets = np.ascontiguousarray(tets, dtype=np.int64)  # (T, 4)
        # (3, 3) or None for an axis-aligned grid (then the index is (p - origin) / spacing).
        self.world_to_index = (None if world_to_index is None else
                               np.asarray(world_to_index, dtype=np.float64).reshape(3, 3))

    @property
    def dims(self):
        """Samples per axis, x first (the volume array is z-major)."""
        nz, ny, nx = self.volume.shape
        return np.array([nx, ny, nz], dtype=np.int64)


def _load_volume(path):
    try:
        a = np.load(path, allow_pickle=False)
    except (OSError, ValueError) as e:
        raise CaseError(f"{path}: {e}") from e
    if a.ndim != 3 or a.dtype != np.float64 or min(a.shape) < 2:
        raise CaseError(f"{path}: {a.dtype} array of shape {a.shape}; expected float64 "
                        "(nz, ny, nx) with at least 2 samples per axis")
    if not np.isfinite(a).all():
        raise CaseError(f"{path}: holds a sample that is not finite")
    return a


_VTK_TETRA = 10


def _vtu_array(element, path, header_dtype):
    """The values of one <DataArray> (ascii, or inline base64 binary without compression)."""
    kind = {"Float64": "<f8", "Float32": "<f4", "Int64": "<i8", "Int32": "<i4", "UInt64": "<u8",
            "UInt32": "<u4", "UInt8": "u1", "Int8": "i1"}.get(element.get("type"))
    name = element.get("Name")
    if kind is None:
        raise CaseError(f"{path}: DataArray {name}: type {element.get('type')} is not read")
    text = element.text or ""
    if element.get("format", "ascii") == "ascii":
        return np.array(text.split(), dtype=np.float64).astype(kind)
    if element.get("format") != "binary":
        raise CaseError(f"{path}: DataArray {name}: format {element.get('format')} is not read")
    raw = base64.b64decode("".join(text.split()))
    header = np.dtype(header_dtype).itemsize
    if len(raw) < header:
        raise CaseError(f"{path}: DataArray {name}: shorter than its header")
    size = int(np.frombuffer(raw[:header], dtype=header_dtype)[0])
    if size > len(raw) - header or size % np.dtype(kind).itemsize:
        raise CaseError(f"{path}: DataArray {name}: header says {size} bytes, "
                        f"{len(raw) - header} follow")
    return np.frombuffer(raw[header:header + size], dtype=kind)


def read_vtu(path):
    """The tets of a .vtu file: points (V, 3) float64, tets (T, 4) int64; other cells ignored."""
    try:
        root = ET.parse(path).getroot()
    except (OSError, ET.ParseError) as e:
        raise CaseError(f"{path}: {e}") from e
    if root.get("compressor") or root.find(".//AppendedData") is not None:
        raise CaseError(f"{path}: compressed or appended data is not read")
    if root.get("byte_order", "LittleEndian") != "LittleEndian":
        raise CaseError(f"{path}: only LittleEndian is read")
    header = "<u8" if root.get("header_type") == "UInt64" else "<u4"
    piece = root.find("UnstructuredGrid/Piece")
    if piece is None:
        raise CaseError(f"{path}: no UnstructuredGrid/Piece")

    def array(where, name):
        for e in piece.findall(where + "/DataArray"):
            if e.get("Name") == name or (name == "Points" and where == "Points"):
                return _vtu_array(e, path, header)
        raise CaseError(f"{path}: no {where} array {name}")

    points = array("Points", "Points").astype(np.float64).reshape(-1, 3)
    connectivity = array("Cells", "connectivity").astype(np.int64)
    offsets = array("Cells", "offsets").astype(np.int64)
    types = array("Cells", "types").astype(np.int64)
    starts = np.concatenate([[0], offsets[:-1]])
    keep = (types == _VTK_TETRA) & (offsets - starts == 4)
    tets = connectivity[starts[keep][:, None] + np.arange(4)]
    if tets.size and (tets.min() < 0 or tets.max() >= len(points)):
        raise CaseError(f"{path}: a tet refers to a vertex outside [0, {len(points)})")
    return points, tets


def write_vtu(path, points, tets, values):
    """Writes the mesh as tetrefine's FormatVtu does: inline base64, UInt64 headers."""

    def array(attributes, a):
        raw = np.ascontiguousarray(a).tobytes()
        data = base64.b64encode(np.array([len(raw)], dtype="<u8").tobytes() + raw).decode()
        return f'        <DataArray {attributes} format="binary">\n          {data}\n' \
               '        </DataArray>\n'

    t = len(tets)
    text = ('<?xml version="1.0"?>\n<VTKFile type="UnstructuredGrid" version="1.0" '
            'byte_order="LittleEndian" header_type="UInt64">\n  <UnstructuredGrid>\n'
            f'    <Piece NumberOfPoints="{len(points)}" NumberOfCells="{t}">\n'
            '      <PointData Scalars="value">\n' +
            array('type="Float64" Name="value"', values.astype("<f8")) +
            '      </PointData>\n      <Points>\n' +
            array('type="Float64" Name="Points" NumberOfComponents="3"', points.astype("<f8")) +
            '      </Points>\n      <Cells>\n' +
            array('type="Int64" Name="connectivity"', tets.astype("<i8")) +
            array('type="Int64" Name="offsets"', 4 * np.arange(1, t + 1, dtype="<i8")) +
            array('type="UInt8" Name="types"', np.full(t, _VTK_TETRA, dtype="u1")) +
            '      </Cells>\n    </Piece>\n  </UnstructuredGrid>\n</VTKFile>\n')
    with open(path, "w", encoding="ascii") as f:
        f.write(text)


def load_case(directory):
    """Reads a case directory (see the module doc); raises CaseError naming the bad file."""
    meta_path = os.path.join(directory, "case.json")
    try:
        with open(meta_path, encoding="utf-8") as f:
            meta = json.load(f)
        origin, spacing, norm = meta["origin"], meta["spacing"], float(meta["norm_coeff"])
    except (OSError, ValueError, KeyError, TypeError) as e:
        raise CaseError(f"{meta_path}: {e!r}") from e
    if len(origin) != 3 or len(spacing) != 3 or min(spacing) <= 0 or not norm > 0:
        raise CaseError(f"{meta_path}: origin/spacing need 3 values, spacing and norm_coeff > 0")
    volume = _load_volume(os.path.join(directory, "volume.npy"))
    points, tets = read_vtu(os.path.join(directory, "mesh.vtu"))
    if len(tets) == 0:
        raise CaseError(f"{directory}/mesh.vtu: no tetrahedra")
    world_to_index = meta.get("world_to_index")
    if world_to_index is not None and (len(world_to_index) != 9 or
                                       not all(np.isfinite(world_to_index))):
        raise CaseError(f"{meta_path}: world_to_index needs 9 finite values")
    return Case(volume, origin, spacing, norm, points, tets, world_to_index)


def orient_positively(points, tets):
    """The tets with their last two vertices swapped where the signed volume is negative."""
    _, vol6 = mean_ratio(points, tets)
    out = tets.copy()
    flip = vol6 < 0
    out[flip, 2], out[flip, 3] = tets[flip, 3], tets[flip, 2]
    return out


def sample(case, p):
    """Trilinear value at world points p (..., 3), as core's Volume::Sample (clamped to the box)."""
    if case.world_to_index is None:
        u = (p - case.origin) / case.spacing  # Volume::ContinuousIndex, axis-aligned
    else:
        # Volume::ContinuousIndex, oblique: m[r][0] d0 + m[r][1] d1 + m[r][2] d2, left to right
        # (numpy neither fuses nor reorders elementwise operations, so the bits are core's).
        d = p - case.origin
        m = case.world_to_index
        u = np.stack([m[r, 0] * d[..., 0] + m[r, 1] * d[..., 1] + m[r, 2] * d[..., 2]
                      for r in range(3)], axis=-1)
    dims = case.dims
    cell = []
    t = []
    for a in range(3):
        x = np.clip(u[..., a], 0.0, float(dims[a] - 1))
        c = np.minimum(x.astype(np.int64), dims[a] - 2)  # x >= 0: truncation is floor
        cell.append(c)
        t.append(x - c)
    nx, ny = int(dims[0]), int(dims[1])
    flat = case.volume.reshape(-1)
    base = cell[0] + nx * (cell[1] + ny * cell[2])
    dy, dz = nx, nx * ny

    def lerp(a, b, s):
        return a * (1.0 - s) + b * s

    c00 = lerp(flat[base], flat[base + 1], t[0])
    c10 = lerp(flat[base + dy], flat[base + dy + 1], t[0])
    c01 = lerp(flat[base + dz], flat[base + dz + 1], t[0])
    c11 = lerp(flat[base + dz + dy], flat[base + dz + dy + 1], t[0])
    return lerp(lerp(c00, c10, t[1]), lerp(c01, c11, t[1]), t[2])


def unique_edges(tets):
    """The mesh's unique edges as an (E, 2) array of vertex pairs, smaller index first."""
    a = tets[:, [0, 0, 0, 1, 1, 2]].ravel()
    b = tets[:, [1, 2, 3, 2, 3, 3]].ravel()
    lo, hi = np.minimum(a, b), np.maximum(a, b)
    # One int64 key per pair: np.unique on rows (axis=0) is an order of magnitude slower.
    span = int(tets.max()) + 1 if tets.size else 1
    keys = np.unique(lo * span + hi)
    return np.stack([keys // span, keys % span], axis=1)


def midpoint_errors(case, points, values, edges):
    """Eq. 3 at each edge's midpoint: |trilinear(mid) - (v_a + v_b) / 2| / normCoeff, (E,)."""
    a, b = edges[:, 0], edges[:, 1]
    mid = 0.5 * (points[a] + points[b])
    return np.abs(sample(case, mid) - 0.5 * (values[a] + values[b])) / case.norm_coeff


def lattice_barycentrics(n=LATTICE_N):
    """The points (i, j, k, l) / n, i + j + k + l = n, in core/lattice.cc's order: (P, 4)."""
    rows = [(i, j, k, n - i - j - k)
            for i in range(n + 1) for j in range(n + 1 - i) for k in range(n + 1 - i - j)]
    return np.array(rows, dtype=np.float64) * (1.0 / n)


def mean_ratio(points, tets):
    """Mean-ratio quality 12 (3 v)^(2/3) / sum of squared edge lengths per tet, (T,)."""
    a, b, c, d = (points[tets[:, i]] for i in range(4))
    u, v, w = b - a, c - a, d - a
    vol6 = (u[:, 0] * (v[:, 1] * w[:, 2] - v[:, 2] * w[:, 1]) -
            u[:, 1] * (v[:, 0] * w[:, 2] - v[:, 2] * w[:, 0]) +
            u[:, 2] * (v[:, 0] * w[:, 1] - v[:, 1] * w[:, 0]))
    volume = np.abs(vol6) / 6.0

    def sq(p, q):
        r = p - q
        return r[:, 0] * r[:, 0] + r[:, 1] * r[:, 1] + r[:, 2] * r[:, 2]

    sum_l2 = sq(a, b) + sq(a, c) + sq(a, d) + sq(b, c) + sq(b, d) + sq(c, d)
    with np.errstate(divide="ignore", invalid="ignore"):
        eta = 12.0 * np.cbrt(9.0 * volume * volume) / sum_l2
    return np.where(sum_l2 > 0.0, eta, 0.0), vol6


def lattice_stats(case, points, tets, values, epsilon, n=LATTICE_N):
    """Discrepancy on the barycentric lattice of every tet (core SampleLattice, all tets)."""
    bary = lattice_barycentrics(n)
    total, count, above, worst = 0.0, 0, 0, 0.0
    for begin in range(0, len(tets), LATTICE_CHUNK):
        t = tets[begin:begin + LATTICE_CHUNK]
        x = np.zeros((len(t), len(bary), 3))
        approx = np.zeros((len(t), len(bary)))
        for c in range(4):  # summed corner by corner, as core does
            x += bary[None, :, c, None] * points[t[:, c]][:, None, :]
            approx += bary[None, :, c] * values[t[:, c]][:, None]
        err = np.abs(sample(case, x) - approx) / case.norm_coeff
        total += float(err.sum())
        count += err.size
        above += int(np.count_nonzero(err > epsilon))
        worst = max(worst, float(err.max()))
    return {"n": n, "tets_sampled": len(tets), "points_sampled": count, "max_error": worst,
            "mean_error": total / count if count else 0.0,
            "share_above_epsilon": above / count if count else 0.0}


def score_mesh(case, points, tets, epsilon):
    """What the reproduction reports for a result mesh: size, midpoint and lattice error, quality."""
    values = sample(case, points)
    err = midpoint_errors(case, points, values, unique_edges(tets))
    eta, vol6 = mean_ratio(points, tets)
    return {
        "tets": int(len(tets)),
        "vertices": int(len(points)),
        "midpoint_max": float(err.max()) if err.size else 0.0,
        "midpoint_mean": float(err.mean()) if err.size else 0.0,
        "lattice": lattice_stats(case, points, tets, values, epsilon),
        "quality": {"min": float(eta.min()), "mean": float(eta.mean()), "count": int(len(tets))},
        "volume": float(np.abs(vol6).sum() / 6.0),
    }


# --- DOLFINx --------------------------------------------------------------------------------------


def dolfinx_available():
    """True when python3-dolfinx can be imported by this interpreter."""
    try:
        import dolfinx.mesh  # noqa: F401  pylint: disable=import-outside-toplevel,unused-import
    except ImportError:
        return False
    return True


def _to_dolfinx(points, tets):
    from mpi4py import MPI  # pylint: disable=import-outside-toplevel
    import dolfinx.mesh  # pylint: disable=import-outside-toplevel
    import ufl  # pylint: disable=import-outside-toplevel
    domain = ufl.Mesh(ufl.VectorElement("Lagrange", ufl.tetrahedron, 1))
    return dolfinx.mesh.create_mesh(MPI.COMM_SELF, tets, points, domain)


def _arrays(mesh):
    """Geometry of a P1 DOLFINx mesh: points (V, 3), tets (T, 4) into them, and its topology's
    edges (E, 2) as geometry node indices (their order is the order refine() takes marks in)."""
    topology = mesh.topology
    topology.create_connectivity(3, 0)
    topology.create_entities(1)
    c2v = topology.connectivity(3, 0).array.reshape(-1, 4)
    dofs = mesh.geometry.dofmap.array.reshape(-1, 4)
    num_vertices = topology.index_map(0).size_local + topology.index_map(0).num_ghosts
    v2g = np.full(num_vertices, -1, dtype=np.int64)
    v2g[c2v.ravel()] = dofs.ravel()
    # P1 geometry lists each cell's nodes in its topology vertices' order; if a DOLFINx version
    # did otherwise, the edge coordinates below would be wrong, so check instead of assuming.
    if not np.array_equal(v2g[c2v], dofs) or (v2g < 0).any():
        raise RuntimeError("DOLFINx topology vertices and geometry nodes do not correspond")
    num_edges = topology.index_map(1).size_local
    e2v = topology.connectivity(1, 0).array.reshape(-1, 2)[:num_edges]
    return mesh.geometry.x, dofs.astype(np.int64), v2g[e2v]


def plaza_refine(case, epsilon, max_rounds=32, max_tets=2_000_000, log=None):
    """Rounds of midpoint marks and Plaza refinement (see the module doc). Returns the summary
    (rounds, stop_reason, seconds, per-round statistics) and the final (points, tets)."""
    import dolfinx  # pylint: disable=import-outside-toplevel
    import dolfinx.mesh  # pylint: disable=import-outside-toplevel
    start = time.perf_counter()
    mesh = _to_dolfinx(case.points, case.tets)
    setup_seconds = time.perf_counter() - start
    start = time.perf_counter()
    per_round = []
    stop = MAX_ROUNDS
    rounds = 0
    while True:
        round_start = time.perf_counter()
        points, tets, edges = _arrays(mesh)
        values = sample(case, points)
        err = midpoint_errors(case, points, values, edges)
        marked = np.flatnonzero(err > epsilon).astype(np.int32)
        if marked.size == 0:
            stop = CONVERGED
            break
        if rounds >= max_rounds:
            stop = MAX_ROUNDS
            break
        refined = dolfinx.mesh.refine(mesh, marked, redistribute=False)
        tets_out = refined.topology.index_map(3).size_local
        record = {"round": rounds + 1, "tets_in": int(len(tets)), "edges": int(len(edges)),
                  "marked_edges": int(marked.size), "midpoint_max": float(err.max()),
                  "midpoint_mean": float(err.mean()), "tets_out": int(tets_out),
                  "seconds": time.perf_counter() - round_start}
        if tets_out > max_tets:
            stop = TET_BUDGET
            record["applied"] = False
            per_round.append(record)
            break
        record["applied"] = True
        per_round.append(record)
        mesh = refined
        rounds += 1
        if log:
            log(f"plaza round {rounds}: {len(tets)} -> {tets_out} tets, {marked.size} of "
                f"{len(edges)} edges marked, midpoint max {err.max():.4f}")
    seconds = time.perf_counter() - start
    summary = {
        "method": "plaza",
        "dolfinx_version": dolfinx.__version__,
        "epsilon": epsilon,
        "norm_coeff": case.norm_coeff,
        "max_rounds": max_rounds,
        "max_tets": max_tets,
        "input_tets": int(len(case.tets)),
        "rounds": rounds,
        "stop_reason": stop,
        "seconds": seconds,
        "setup_seconds": setup_seconds,
        "per_round": per_round,
    }
    return summary, (np.array(points), tets)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--check", action="store_true",
                        help="only say whether python3-dolfinx imports: exit 0, else 3")
    parser.add_argument("--score-only", action="store_true",
                        help="score the input mesh as it is (no refinement; needs numpy only)")
    parser.add_argument("--case", help="case directory (volume.npy, case.json, mesh.vtu)")
    parser.add_argument("--epsilon", type=float, help="relative tolerance, > 0")
    parser.add_argument("--max-rounds", type=int, default=32)
    parser.add_argument("--max-tets", type=int, default=2_000_000)
    parser.add_argument("--output", help="result JSON (default: stdout)")
    parser.add_argument("--mesh-out", help="write the final mesh to this .vtu file")
    parser.add_argument("--quiet", action="store_true", help="no progress lines on stderr")
    args = parser.parse_args(argv)
    if not args.check and (args.case is None or args.epsilon is None):
        parser.error("--case and --epsilon are required")
    if not args.check and (not args.epsilon > 0 or args.max_rounds < 0 or args.max_tets < 1):
        parser.error("--epsilon must be > 0, --max-rounds >= 0, --max-tets >= 1")
    if np is None:
        print(f"{sys.argv[0]}: python3-numpy is missing for {sys.executable} "
              "(bash bench/peers/install-peers.sh)", file=sys.stderr)
        return EXIT_DOLFINX_MISSING
    if not args.score_only and not dolfinx_available():
        print(f"{sys.argv[0]}: python3-dolfinx is missing for {sys.executable} "
              "(bash bench/peers/install-peers.sh)", file=sys.stderr)
        return EXIT_DOLFINX_MISSING
    if args.check:
        return 0
    try:
        case = load_case(args.case)
    except CaseError as e:
        print(f"{sys.argv[0]}: {e}", file=sys.stderr)
        return 2

    def log(line):
        if not args.quiet:
            print(line, file=sys.stderr, flush=True)

    if args.score_only:
        summary, (points, tets) = {"method": "none", "epsilon": args.epsilon,
                                   "norm_coeff": case.norm_coeff}, (case.points, case.tets)
    else:
        summary, (points, tets) = plaza_refine(case, args.epsilon, args.max_rounds,
                                               args.max_tets, log)
    initial_quality, _ = mean_ratio(case.points, case.tets)
    summary["initial_quality"] = {"min": float(initial_quality.min()),
                                  "mean": float(initial_quality.mean()),
                                  "count": int(len(case.tets))}
    summary.update(score_mesh(case, points, tets, args.epsilon))
    if args.mesh_out:
        write_vtu(args.mesh_out, points, orient_positively(points, tets), sample(case, points))
    text = json.dumps(summary, indent=1)
    if args.output:
        with open(args.output, "w", encoding="utf-8") as f:
            f.write(text + "\n")
    else:
        print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
