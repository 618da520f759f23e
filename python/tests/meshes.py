"""Test inputs built with numpy: box meshes of 5 tets per cell, and volumes."""

import numpy as np

# The two ways to cut a cube (corner bits: 1 = +x, 2 = +y, 4 = +z) into 5 tets; neighbouring
# cells alternate so that their shared faces have the same diagonal.
_EVEN_CORNERS, _ODD_CORNERS = (0, 3, 5, 6), (1, 2, 4, 7)


def box_mesh(lo, hi, cells):
    """The box [lo, hi] cut into cells[0] x cells[1] x cells[2] cells of 5 positively oriented
    tets each. Returns points (n, 3) float64 and tets (m, 4) int64."""
    axes = [np.linspace(lo[a], hi[a], cells[a] + 1) for a in range(3)]
    x, y, z = np.meshgrid(*axes, indexing="ij")
    points = np.stack([x.ravel(order="F"), y.ravel(order="F"), z.ravel(order="F")], axis=1)
    nx, ny = cells[0] + 1, cells[1] + 1
    i, j, k = np.meshgrid(*(np.arange(c) for c in cells), indexing="ij")
    i, j, k = i.ravel(), j.ravel(), k.ravel()
    corner = [(i + (b & 1)) + nx * ((j + ((b >> 1) & 1)) + ny * (k + (b >> 2))) for b in range(8)]
    corner = np.stack(corner, axis=1)
    even = (i + j + k) % 2 == 0
    tets = []
    for parity, corners, center in ((even, _EVEN_CORNERS, _ODD_CORNERS),
                                    (~even, _ODD_CORNERS, _EVEN_CORNERS)):
        c = corner[parity]
        for b in corners:
            tets.append(c[:, [b, b ^ 1, b ^ 2, b ^ 4]])
        tets.append(c[:, list(center)])
    tets = np.concatenate(tets)
    p = points[tets]
    volume6 = np.einsum("ij,ij->i", p[:, 1] - p[:, 0],
                        np.cross(p[:, 2] - p[:, 0], p[:, 3] - p[:, 0]))
    inverted = volume6 < 0
    tets[inverted] = tets[inverted][:, [0, 1, 3, 2]]
    return points, tets.astype(np.int64)


def smooth_volume(shape):
    """float64 samples of a smooth field, indexed [x, y, z]."""
    x, y, z = np.meshgrid(*(np.arange(n, dtype=np.float64) for n in shape), indexing="ij")
    return np.sin(0.45 * x) * np.cos(0.35 * y) + 0.02 * z * z + 0.3 * np.sin(0.8 * y + 0.6 * z)


def noise_volume(shape, seed=7):
    """Seeded uniform noise in [0, 1000), indexed [x, y, z]: features as sharp as a voxel, so
    refinement has work to do in every iteration."""
    return np.random.default_rng(seed).uniform(0.0, 1000.0, size=shape)
