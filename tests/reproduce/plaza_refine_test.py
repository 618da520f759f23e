#!/usr/bin/python3
"""Tests of bench/peers/plaza_refine.py, the Plaza baseline of the reproduction, on a tiny case.

The refinement needs python3-dolfinx; without it this test exits with SKIP_CODE, which CTest
reports as skipped (SKIP_RETURN_CODE), after saying why. What is checked: the result is conformal
(every interior face shared by exactly two tets, the boundary's area unchanged), fills the same
volume with positively oriented tets, every edge the first round marked was split at its midpoint,
a converged run has no edge above epsilon, and the round and tet caps stop it as documented."""

import argparse
import json
import os
import subprocess
import sys
import tempfile

import numpy as np

SKIP_CODE = 77


def fail(message):
    print("FAIL: " + message)
    sys.exit(1)


def check(condition, message):
    if not condition:
        fail(message)


def five_tet_cube_mesh(cells, size):
    """cells^3 cubes of edge `size` from the origin, 5 tets each, alternating so faces match."""
    index = {}
    points = []

    def vertex(i, j, k):
        if (i, j, k) not in index:
            index[(i, j, k)] = len(points)
            points.append((i * size, j * size, k * size))
        return index[(i, j, k)]

    even = [(0, 1, 2, 4), (1, 3, 2, 7), (1, 4, 5, 7), (2, 4, 7, 6), (1, 2, 4, 7)]
    odd = [(0, 1, 3, 5), (0, 3, 2, 6), (0, 5, 6, 4), (3, 6, 5, 7), (0, 3, 5, 6)]
    tets = []
    for i in range(cells):
        for j in range(cells):
            for k in range(cells):
                corner = [vertex(i + a, j + b, k + c)
                          for c in (0, 1) for b in (0, 1) for a in (0, 1)]
                for t in (even if (i + j + k) % 2 == 0 else odd):
                    tets.append([corner[q] for q in t])
    return np.array(points, dtype=np.float64), np.array(tets, dtype=np.int64)


def faces_of(tets):
    f = np.concatenate([tets[:, [0, 1, 2]], tets[:, [0, 1, 3]], tets[:, [0, 2, 3]],
                        tets[:, [1, 2, 3]]])
    return np.sort(f, axis=1)


def boundary_area(points, tets):
    faces, counts = np.unique(faces_of(tets), axis=0, return_counts=True)
    check(counts.max() <= 2, "a face is shared by more than two tets")
    b = faces[counts == 1]
    cross = np.cross(points[b[:, 1]] - points[b[:, 0]], points[b[:, 2]] - points[b[:, 0]])
    return 0.5 * np.linalg.norm(cross, axis=1).sum()


def write_case(pr, directory, volume, points, tets):
    os.makedirs(directory, exist_ok=True)
    np.save(os.path.join(directory, "volume.npy"), volume)
    with open(os.path.join(directory, "case.json"), "w", encoding="utf-8") as f:
        json.dump({"origin": [0.0, 0.0, 0.0], "spacing": [1.0, 1.0, 1.0],
                   "norm_coeff": float(volume.max() - volume.min())}, f)
    pr.write_vtu(os.path.join(directory, "mesh.vtu"), points, tets, np.zeros(len(points)))


def run(script, case, epsilon, out, *extra):
    proc = subprocess.run(["/usr/bin/python3", script, "--case", case, "--epsilon", str(epsilon),
                           "--output", out + ".json", "--mesh-out", out + ".vtu", "--quiet",
                           *extra], capture_output=True, text=True, timeout=300, check=False)
    check(proc.returncode == 0, f"plaza_refine.py exited with {proc.returncode}: {proc.stderr}")
    with open(out + ".json", encoding="utf-8") as f:
        return json.load(f)


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--script", required=True)
    args = parser.parse_args()
    sys.path.insert(0, os.path.dirname(os.path.abspath(args.script)))
    import plaza_refine as pr  # pylint: disable=import-outside-toplevel
    if not pr.dolfinx_available():
        print("SKIP: python3-dolfinx is not installed for /usr/bin/python3 "
              "(bash bench/peers/install-peers.sh)")
        sys.exit(SKIP_CODE)

    # A sphere of radius 3.2 voxels with a sharp wall (trilinear between 0 and 1000) in 9^3
    # samples, meshed by 2^3 cubes of 4 voxels: its wall cuts many edges the midpoint test sees.
    n = 9
    z, y, x = np.meshgrid(np.arange(n), np.arange(n), np.arange(n), indexing="ij")
    volume = np.where((x - 4.2) ** 2 + (y - 3.9) ** 2 + (z - 4.1) ** 2 < 3.2 ** 2, 1000.0, 0.0)
    points, tets = five_tet_cube_mesh(2, 4.0)
    epsilon = 0.1
    with tempfile.TemporaryDirectory() as tmp:
        case_dir = os.path.join(tmp, "case")
        write_case(pr, case_dir, volume, points, tets)
        case = pr.load_case(case_dir)
        check(np.array_equal(case.points, points) and np.array_equal(case.tets, tets),
              "the case's mesh did not read back as written")

        # What round 1 marks, computed from the input.
        values = pr.sample(case, points)
        edges = pr.unique_edges(tets)
        marked = edges[pr.midpoint_errors(case, points, values, edges) > epsilon]
        check(len(marked) > 0, "the test case marks no edge")

        out = os.path.join(tmp, "converged")
        result = run(args.script, case_dir, epsilon, out)
        check(result["stop_reason"] == "converged", f"stop {result['stop_reason']}")
        check(result["rounds"] >= 1, "no round was run")
        check(result["per_round"][0]["marked_edges"] == len(marked),
              "round 1 marked other edges than the midpoint test on the input")
        fine_points, fine_tets = pr.read_vtu(out + ".vtu")
        check(len(fine_tets) == result["tets"] > len(tets), "tet count")

        # Conformal and the same domain: positive volumes adding up to the cube's, each face
        # shared by at most two tets, and the boundary's area that of the cube (a hanging vertex
        # would leave interior faces unmatched and add to it).
        _, vol6 = pr.mean_ratio(fine_points, fine_tets)
        check(vol6.min() > 0, "an output tet is not positively oriented")
        check(abs(vol6.sum() / 6.0 - 8.0 ** 3) < 1e-9 * 8.0 ** 3, "the volume changed")
        area = boundary_area(fine_points, fine_tets)
        check(abs(area - 6 * 8.0 ** 2) < 1e-9 * area, f"boundary area {area} (hanging vertices)")

        # Every marked edge was split at its midpoint: the midpoint is a vertex and no output
        # edge joins the two ends.
        def key(p):
            return tuple(np.round(p, 12))

        vertex_ids = {key(p): i for i, p in enumerate(fine_points)}
        fine_edges = {tuple(e) for e in pr.unique_edges(fine_tets)}
        for a, b in marked:
            mid = 0.5 * (points[a] + points[b])
            check(key(mid) in vertex_ids, f"the midpoint of marked edge {a}-{b} is no vertex")
            ia, ib = vertex_ids[key(points[a])], vertex_ids[key(points[b])]
            check((min(ia, ib), max(ia, ib)) not in fine_edges, f"marked edge {a}-{b} is whole")

        # Converged means no edge of the result above epsilon, and the figures are the result's.
        fine_values = pr.sample(case, fine_points)
        err = pr.midpoint_errors(case, fine_points, fine_values, pr.unique_edges(fine_tets))
        check(err.max() <= epsilon, f"midpoint error {err.max()} above epsilon")
        check(result["midpoint_max"] == err.max(), "midpoint_max is not the result's")
        eta, _ = pr.mean_ratio(fine_points, fine_tets)
        check(result["quality"]["min"] == eta.min(), "quality min is not the result's")
        check(result["lattice"]["points_sampled"] == 165 * len(fine_tets), "lattice points")

        # The caps: one round, then max_rounds; a budget below the first round's size keeps the
        # input (that round is discarded).
        capped = run(args.script, case_dir, epsilon, os.path.join(tmp, "capped"), "--max-rounds",
                     "1")
        check(capped["stop_reason"] == "max_rounds" and capped["rounds"] == 1,
              f"max_rounds: {capped['stop_reason']} after {capped['rounds']}")
        check(capped["tets"] == result["per_round"][0]["tets_out"], "one round's tets")
        budget = run(args.script, case_dir, epsilon, os.path.join(tmp, "budget"), "--max-tets",
                     str(len(tets) + 1))
        check(budget["stop_reason"] == "tet_budget" and budget["rounds"] == 0,
              f"tet_budget: {budget['stop_reason']} after {budget['rounds']}")
        check(budget["tets"] == len(tets), "a refused round changed the mesh")

        # A linear field: trilinear interpolation is exact, nothing is marked.
        write_case(pr, os.path.join(tmp, "linear"), 3.0 * x - 2.0 * y + 0.5 * z, points, tets)
        linear = run(args.script, os.path.join(tmp, "linear"), 0.001, os.path.join(tmp, "lin"))
        check(linear["stop_reason"] == "converged" and linear["rounds"] == 0, "linear field")
        check(linear["lattice"]["max_error"] < 1e-12, "linear field: lattice error")

        # A broken input names its file.
        os.remove(os.path.join(case_dir, "case.json"))
        proc = subprocess.run(["/usr/bin/python3", args.script, "--case", case_dir, "--epsilon",
                               "0.1"], capture_output=True, text=True, timeout=120, check=False)
        check(proc.returncode == 2 and "case.json" in proc.stderr,
              f"missing case.json: exit {proc.returncode}, {proc.stderr!r}")
    print(f"OK: {len(tets)} -> {result['tets']} tets in {result['rounds']} rounds, "
          f"{len(marked)} edges marked in round 1")


if __name__ == "__main__":
    main()
