"""What pipeline authors hold (nibabel images, meshio meshes) to and from refine()'s arrays.

nibabel and meshio are imported only when these functions are called.
"""

import math
import warnings

import numpy as np

from tetrefine._requests import whole_numbers
from tetrefine.errors import invalid

# Relative size below which an off-diagonal affine entry counts as zero; the same rule as the
# C++ readers (client/io/grid_placement.h, kObliqueTolerance): float32 quaternion rounding is
# about 1e-7 of a column's length, a 0.1 degree tilt 1.7e-3.
OBLIQUE_TOLERANCE = 1e-5

# NIfTI xyzt_units spatial unit -> millimetres, as the C++ NIfTI reader converts them.
_MM_PER_UNIT = {"meter": 1000.0, "mm": 1.0, "micron": 0.001, "unknown": 1.0}


class VolumeGrid:
    """A volume ready for Client.refine: data indexed [x, y, z], spacing and origin in world
    millimetres (RAS for NIfTI), direction None (axis-aligned) or a 3x3 matrix whose columns
    are the world directions of the x, y, z index axes."""

    def __init__(self, data, spacing, origin, direction=None):
        self.data = data
        self.spacing = spacing
        self.origin = origin
        self.direction = direction

    def world_box(self):
        """(lo, hi) corners of the sampled box for an axis-aligned grid, world mm."""
        lo = np.asarray(self.origin, dtype=np.float64)
        hi = lo + (np.asarray(self.data.shape) - 1) * np.asarray(self.spacing)
        return lo, hi


def _nifti_pixdim_affine(image):
    """For a NIfTI with neither sform nor qform, the affine tetrefine's reader uses, else None.

    nibabel's image.affine is then its Analyze fallback, which centres the grid and flips x;
    the NIfTI standard's method 1, which the C++ reader follows, puts voxel (i, j, k) at
    (i, j, k) * pixdim from the origin. A zero or non-finite pixdim is read as 1, with a warning,
    as the C++ reader does.
    """
    header = getattr(image, "header", None)
    if header is None or not hasattr(header, "get_sform") or not hasattr(header, "get_qform"):
        return None
    try:
        sform_code = int(header["sform_code"])
        qform_code = int(header["qform_code"])
        pixdim = [float(header["pixdim"][a + 1]) for a in range(3)]
    except (KeyError, ValueError, TypeError, IndexError):
        return None
    if sform_code > 0 or qform_code > 0:
        return None
    affine = np.eye(4)
    for a in range(3):
        size = abs(pixdim[a])
        if not (size > 0.0) or not math.isfinite(size):
            warnings.warn(f"pixdim[{a + 1}] is {pixdim[a]} and the image has no qform or sform: "
                          f"voxel size 1 used along axis {a}")
            size = 1.0
        affine[a, a] = size
    return affine


def _nifti_qform_affine(image):
    """For a NIfTI whose affine is its qform (no sform), that affine as tetrefine's reader
    computes it (nifti1_io's formula), else None.

    nibabel's quaternion arithmetic differs from it in the last bit of some entries, and a
    qform-only oblique image gave points 3e-14 and values 1e-10 away from the CLI's (an outside
    review, 2026-11-28); with the same formula the result is the CLI's to the bit.
    """
    header = getattr(image, "header", None)
    if header is None or not hasattr(header, "get_qform"):
        return None
    try:
        if int(header["sform_code"]) > 0 or int(header["qform_code"]) <= 0:
            return None
        b, c, d = (float(header[k]) for k in ("quatern_b", "quatern_c", "quatern_d"))
        pixdim = [float(header["pixdim"][i]) for i in range(4)]
        offset = [float(header[k]) for k in ("qoffset_x", "qoffset_y", "qoffset_z")]
    except (KeyError, ValueError, TypeError, IndexError):
        return None
    a = 1.0 - (b * b + c * c + d * d)
    if a < 1e-7:
        # Rounding pushed the norm past 1: a 180 degree rotation, renormalised.
        scale = 1.0 / math.sqrt(b * b + c * c + d * d)
        b, c, d = b * scale, c * scale, d * scale
        a = 0.0
    else:
        a = math.sqrt(a)
    rotation = [[a * a + b * b - c * c - d * d, 2 * (b * c - a * d), 2 * (b * d + a * c)],
                [2 * (b * c + a * d), a * a + c * c - b * b - d * d, 2 * (c * d - a * b)],
                [2 * (b * d - a * c), 2 * (c * d + a * b), a * a + d * d - c * c - b * b]]
    qfac = -1.0 if pixdim[0] < 0.0 else 1.0
    sizes = [abs(pixdim[1]), abs(pixdim[2]), qfac * abs(pixdim[3])]
    affine = np.eye(4)
    for r in range(3):
        for col in range(3):
            affine[r, col] = rotation[r][col] * sizes[col]
        affine[r, 3] = offset[r]
    return affine


def _unit_scale(image):
    header = getattr(image, "header", None)
    get_units = getattr(header, "get_xyzt_units", None)
    if get_units is None:
        return 1.0
    return _MM_PER_UNIT.get(get_units()[0], 1.0)


def _samples(image):
    """The image's samples, scaled as the C++ NIfTI reader scales them.

    Unscaled data keeps its stored dtype (int16 stays int16 on the wire). With a slope or an
    intercept, value = slope * stored + intercept is computed in float64 and stored as float32 for
    8/16-bit and float32 data, float64 otherwise (client/io/voxel_decode.cc).
    """
    proxy = image.dataobj
    slope = getattr(proxy, "slope", 1.0)
    inter = getattr(proxy, "inter", 0.0)
    raw = np.asanyarray(proxy.get_unscaled()) if hasattr(proxy, "get_unscaled") else None
    if raw is None:
        return np.asanyarray(proxy)
    slope = 1.0 if slope is None or not math.isfinite(slope) or slope == 0 else float(slope)
    inter = 0.0 if inter is None or not math.isfinite(inter) else float(inter)
    if slope == 1.0 and inter == 0.0:
        return raw
    narrow = raw.dtype.itemsize <= 2 or raw.dtype == np.float32
    scaled = slope * raw.astype(np.float64) + inter
    return scaled.astype(np.float32 if narrow else np.float64)


def _hypot3(x, y, z):
    """std::hypot(x, y, z) as libstdc++ computes it (GCC 10 and later), which the C++ readers use
    for a column's length: Python's math.hypot rounds differently in the last bit, and an oblique
    grid's spacing and direction then differed from the CLI's (a service sweep)."""
    x, y, z = abs(float(x)), abs(float(y)), abs(float(z))
    a = (z if y < z else y) if x < y else (z if x < z else x)
    if a == 0.0:
        return 0.0
    return a * math.sqrt((x / a) * (x / a) + (y / a) * (y / a) + (z / a) * (z / a))


def volume_from_nibabel(image):
    """A VolumeGrid from a nibabel image (NIfTI-1/2, MGH, ...), in its world frame.

    The affine (image.affine; NIfTI: sform, else qform) is applied as tetrefine's own readers
    apply it, so the result equals `tetrefine refine --volume file.nii` to the bit:
      - diagonal up to signs (the usual case, including flipped axes): every axis with a negative
        scale is reversed, so the grid is axis-aligned with positive spacing, direction None;
      - rotated, sheared or permuted ("oblique"): the samples stay as stored, spacing = the
        affine's column lengths, origin = its translation, direction = the unit columns (3x3).
    NIfTI spatial units (metres, microns) are converted to millimetres. A 4-d image with one
    volume (or 5-d with one component) is accepted; more volumes are refused, and so is an
    ANALYZE 7.5 image (no orientation).
    """
    if not (hasattr(image, "dataobj") and hasattr(image, "affine")):
        raise invalid("image", f"expected a nibabel image (e.g. nibabel.load(path)), got "
                      f"{type(image).__name__}; an array has no geometry: use VolumeGrid")
    import nibabel

    header = getattr(image, "header", None)
    if isinstance(header, nibabel.analyze.AnalyzeHeader) and not isinstance(
            header, nibabel.Nifti1Header):
        # nibabel gives ANALYZE 7.5 a made-up, centred affine; the CLI refuses the file.
        raise invalid("image", "an ANALYZE 7.5 image has no orientation; convert it to NIfTI "
                      "with its real affine (the CLI refuses it too)")
    data = _samples(image)
    # Trailing axes of one sample (4-d with one volume, 5-d with one component) are a 3-d
    # volume, as the CLI reads them.
    while data.ndim > 3 and data.shape[-1] == 1:
        data = data[..., 0]
    if data.ndim != 3:
        raise invalid("image", f"expected a 3-d volume, got shape {data.shape}")
    affine = _nifti_pixdim_affine(image)
    if affine is None:
        affine = _nifti_qform_affine(image)
    if affine is None:
        affine = np.asarray(image.affine, dtype=np.float64)
    affine = affine * _unit_scale(image)
    if not np.all(np.isfinite(affine[:3, :4])):
        raise invalid("image", "the affine has a non-finite entry")
    lengths = [_hypot3(affine[0, c], affine[1, c], affine[2, c]) for c in range(3)]
    if not all(length > 0 for length in lengths):
        raise invalid("image", "the affine is singular")
    diagonal = all(abs(affine[r, c]) <= OBLIQUE_TOLERANCE * lengths[c]
                   for c in range(3) for r in range(3) if r != c)
    if not diagonal:
        direction = affine[:3, :3] / np.asarray(lengths)
        return VolumeGrid(data, lengths, [float(x) for x in affine[:3, 3]], direction)
    flip = [affine[a, a] < 0 for a in range(3)]
    first = [data.shape[a] - 1 if flip[a] else 0 for a in range(3)]
    # Summed in the C++ order (translation, then columns 0, 1, 2) for the same bits.
    origin = []
    for row in range(3):
        value = float(affine[row, 3])
        for column in range(3):
            value += float(affine[row, column]) * float(first[column])
        origin.append(value)
    spacing = [abs(float(affine[a, a])) for a in range(3)]
    if any(flip):
        data = data[tuple(slice(None, None, -1) if f else slice(None) for f in flip)]
    return VolumeGrid(data, spacing, origin, None)


def fit_to_volume(points, grid):
    """Points scaled per axis and moved so their bounding box becomes the volume's sampled box
    less one voxel on every side (at most a quarter of the box): what `tetrefine refine
    --fit-mesh-to-volume` does (client/cli/mesh_placement.cc), to the bit for an axis-aligned
    grid. For an oblique grid (direction set) the box is the index box less one sample, mapped
    through the grid's affine (index x reversed when the direction mirrors, so tets keep their
    orientation). For meshes made in their own unit frame. Returns (n, 3) float64.
    """
    if not all(hasattr(grid, a) for a in ("data", "spacing", "origin", "direction")):
        raise invalid("grid", f"expected a VolumeGrid (e.g. from volume_from_nibabel), got "
                      f"{type(grid).__name__}")
    points = np.asarray(points, dtype=np.float64)
    if points.ndim != 2 or points.shape[1] != 3 or len(points) == 0:
        raise invalid("points", f"expected shape (n, 3) with n > 0, got {points.shape}")
    finite = np.isfinite(points).all(axis=1)
    if not finite.all():
        raise invalid("points", f"points[{int(np.argmin(finite))}] is not finite")
    p_lo, p_hi = points.min(axis=0), points.max(axis=0)
    flat = ~(p_hi > p_lo)
    if flat.any():
        raise invalid("points", f"the mesh is flat along axis {'xyz'[int(np.argmax(flat))]}, "
                      "so it cannot be fitted to the volume")
    t = (points - p_lo) / (p_hi - p_lo)
    spacing = np.asarray(grid.spacing, dtype=np.float64)
    if grid.direction is None:
        lo, hi = grid.world_box()
        margin = np.minimum(spacing, 0.25 * (hi - lo))
        to_lo, to_hi = lo + margin, hi - margin
        # The extremes map exactly onto the target box, whatever the rounding in between.
        return np.where(t <= 0.0, to_lo, np.where(t >= 1.0, to_hi, to_lo + t * (to_hi - to_lo)))
    direction = np.asarray(grid.direction, dtype=np.float64).reshape(3, 3)
    extent = np.asarray(grid.data.shape[:3], dtype=np.float64) - 1
    margin = np.minimum(1.0, 0.25 * extent)
    to_lo, to_hi = margin, extent - margin
    if np.linalg.det(direction) < 0:
        t[:, 0] = 1.0 - t[:, 0]
    u = np.where(t <= 0.0, to_lo, np.where(t >= 1.0, to_hi, to_lo + t * (to_hi - to_lo)))
    # origin + direction * (spacing * u), summed as core's WorldOfIndex sums it (columns 0, 1,
    # then 2, then the origin), for the CLI's bits: a matrix product summed otherwise and moved
    # 120 of 448 vertices by up to 3e-14 (a service sweep).
    s = u * spacing
    origin = np.asarray(grid.origin, dtype=np.float64)
    world = np.empty_like(s)
    for row in range(3):
        world[:, row] = origin[row] + (direction[row, 0] * s[:, 0] + direction[row, 1] * s[:, 1]
                                       + direction[row, 2] * s[:, 2])
    return world


class TetMesh:
    """A tet mesh ready for Client.refine: points (n, 3) float64, tets (m, 4) int64, labels
    (m,) int32 or None, values (n,) float64 or None (a "value" point array). label_name is the
    cell array the labels came from (None without labels); region_names maps a label to its
    name where the file names its regions (Gmsh's physical volumes, meshio's field_data), else
    it is empty: pass both to RefineResult.to_meshio to write them back."""

    def __init__(self, points, tets, labels=None, values=None, label_name=None,
                 region_names=None):
        self.points = points
        self.tets = tets
        self.labels = labels
        self.values = values
        self.label_name = label_name
        self.region_names = dict(region_names or {})


# The cell-data names taken as region labels, the first found winning, compared without case:
# the CLI's list (client/io/label_names.cc), so that a file gives the same labels through
# meshio as through `tetrefine refine` (tests/test_adapters.py checks the two agree).
LABEL_NAMES = ("gmsh:physical", "medit:ref", "tetgen:ref", "CellEntityIds", "region", "regions",
               "labels", "label", "MaterialIds", "material", "materials", "subdomain",
               "cell_scalars")


# meshio's volume cell types other than "tetra" (tetra10, hexahedron, hexahedron27, wedge,
# pyramid, polyhedron8, ...).
_VOLUME_CELL_PREFIXES = ("tetra", "hexahedron", "wedge", "pyramid", "polyhedron")


def mesh_from_meshio(mesh, label_name=None):
    """A TetMesh from a meshio.Mesh: every "tetra" cell block in order (surface and line cells,
    e.g. boundary triangles, are skipped; other volume cells refuse the mesh). labels from cell
    data `label_name`, or when None the first of LABEL_NAMES the tetra blocks carry; None when
    there is none."""
    if not all(hasattr(mesh, a) for a in ("points", "cells", "cell_data", "point_data")):
        raise invalid("mesh", f"expected a meshio.Mesh, got {type(mesh).__name__}")
    points = np.asarray(mesh.points, dtype=np.float64)
    if points.ndim != 2 or points.shape[1] != 3:
        raise invalid("mesh", f"expected 3-d points, got shape {points.shape}")
    blocks = [i for i, block in enumerate(mesh.cells) if block.type == "tetra"]
    if not blocks:
        found = sorted({block.type for block in mesh.cells})
        raise invalid("mesh", f"no tetra cells (cell types: {', '.join(found) or 'none'})")
    # Other volume cells (quadratic tets, hexahedra, wedges, pyramids) are part of the domain:
    # dropping them would refine a mesh with a hole, so they refuse it, as the CLI's readers do.
    others = {}
    for block in mesh.cells:
        if block.type != "tetra" and block.type.startswith(_VOLUME_CELL_PREFIXES):
            others[block.type] = others.get(block.type, 0) + len(block.data)
    if others:
        tet_count = sum(len(mesh.cells[i].data) for i in blocks)
        found = ", ".join(f"{n} {t}" for t, n in sorted(others.items()))
        raise invalid("mesh", f"{found} cells beside {tet_count} tetra: only linear tets are "
                      "refined; split or remove the other volume cells first")
    for i in blocks:
        data = np.asarray(mesh.cells[i].data)
        if data.dtype.kind == "f" and not whole_numbers(data).all():
            bad = np.argwhere(~whole_numbers(data))[0]
            raise invalid("mesh", f"tetra block {i} holds vertex index {data[tuple(bad)]} (cell "
                          f"{bad[0]}), not a whole number")
        if data.dtype.kind not in "iuf":
            raise invalid("mesh", f"tetra block {i} has dtype {data.dtype}, expected integers")
    tets = np.concatenate([np.asarray(mesh.cells[i].data, dtype=np.int64) for i in blocks])
    if label_name is not None:
        names = [label_name]
    else:
        by_lower = {}
        for key in mesh.cell_data:
            by_lower.setdefault(key.lower(), key)
        names = [by_lower[n.lower()] for n in LABEL_NAMES if n.lower() in by_lower]
    labels = None
    found_name = None
    for name in names:
        arrays = mesh.cell_data.get(name)
        if arrays is not None:
            labels = np.concatenate([_labels_of_block(name, mesh.cells[i], arrays[i])
                                     for i in blocks])
            found_name = name
            break
    else:
        if label_name is not None:
            raise invalid("label_name", f"the mesh has no cell data {label_name!r} (it has "
                          f"{', '.join(sorted(mesh.cell_data)) or 'none'})")
    values = mesh.point_data.get("value")
    if values is not None:
        values = np.asarray(values, dtype=np.float64)
        if values.shape not in ((len(points),), (len(points), 1)):
            raise invalid("mesh", f"point data 'value' has shape {values.shape}, expected one "
                          f"number per point ({len(points)},)")
        values = values.reshape(-1)
    region_names = {}
    if found_name is not None and found_name.lower() == "gmsh:physical":
        kept_before = set(np.unique(labels).tolist())
        tets, labels = _drop_physical_copies(mesh, blocks, tets, labels)
        region_names = _region_names(mesh, labels, kept_before)
    return TetMesh(points, tets, labels, values, found_name, region_names)


def _drop_physical_copies(mesh, blocks, tets, labels):
    """Gmsh's MSH 2 writer repeats each element of a volume that is in several physical groups,
    once per group, and meshio reads every copy: the server then refused the mesh ("an element
    listed twice") where the CLI reads the file. As the CLI does (client/io/gmsh_reader.cc), a
    tet keeps its first group's label: a later tet of the same elementary entity on the same
    nodes with another physical label is dropped, with a warning naming the groups. One with the
    same label is a real repeat, left for the server to name. (An outside review, 2026-11-29.)"""
    entities = mesh.cell_data.get("gmsh:geometrical")
    if entities is None:
        return tets, labels
    entity = np.concatenate([np.asarray(entities[i]).reshape(-1) for i in blocks])
    if entity.shape != (len(tets),):
        return tets, labels
    keys = np.concatenate([entity.astype(np.int64)[:, None], np.sort(tets, axis=1)], axis=1)
    _, first, inverse = np.unique(keys, axis=0, return_index=True, return_inverse=True)
    if len(first) == len(tets):
        return tets, labels
    inverse = inverse.reshape(-1)
    copy = np.ones(len(tets), dtype=bool)
    copy[first] = False
    copy &= labels != labels[first[inverse]]
    if not copy.any():
        return tets, labels
    groups = sorted({(int(entity[i]), int(labels[i])) for i in np.flatnonzero(copy)})
    listed = ", ".join(f"{g} of volume {e}" for e, g in groups[:4])
    if len(groups) > 4:
        listed += f" and {len(groups) - 4} more"
    warnings.warn(f"not carried to the output: physical group{'s' if len(groups) > 1 else ''} "
                  f"{listed} (a tet keeps one label: its volume's first physical group; "
                  f"{int(copy.sum())} repeated tets dropped)")
    return tets[~copy], labels[~copy]


def _region_names(mesh, labels, labelled):
    """Gmsh's physical volume names from meshio's field_data ({name: [tag, dimension]}), for
    the tags the labels use. Surface and line groups share tags with volumes in Gmsh's
    numbering, so only dimension 3 counts. The outside review of 2026-11-29 found the names
    lost between meshio.read and meshio.write; the CLI's .msh output kept them.

    A named physical volume that no tet was read with (`labelled`: the labels before
    _drop_physical_copies, which warns of its own) is named in a warning, as the CLI names the
    groups it does not keep: meshio 5.0's MSH 4.1 reader keeps only a volume's first physical
    group, so a second group vanished without a word (an outside review, 2026-11-29)."""
    field_data = getattr(mesh, "field_data", None) or {}
    used = set(np.unique(labels).tolist())
    names = {}
    unread = []
    for name, entry in field_data.items():
        entry = np.asarray(entry).reshape(-1)
        if len(entry) < 2 or int(entry[1]) != 3:
            continue
        if int(entry[0]) in used:
            # A tag named twice keeps its first name (the file's order), as Gmsh's reader does.
            names.setdefault(int(entry[0]), str(name))
        elif int(entry[0]) not in labelled:
            unread.append(f"{int(entry[0])} ({name!r})")
    if unread:
        listed = ", ".join(unread[:4]) + (f" and {len(unread) - 4} more" if len(unread) > 4 else "")
        warnings.warn(f"not carried to the output: physical volume{'s' if len(unread) > 1 else ''}"
                      f" {listed}: no tet was read with it (empty, or a volume's second group:"
                      " meshio's MSH 4.1 reader keeps a volume's first physical group only)")
    return names


def _labels_of_block(name, block, array):
    """One tetra block's labels as int32: one whole number per cell that int32 holds. A cast
    alone wrapped 2**32 + 7 to 7 (merging regions) and truncated 2.7 to 2."""
    labels = np.asarray(array)
    if labels.ndim == 2 and labels.shape[1] == 1:
        labels = labels.reshape(-1)
    if labels.shape != (len(block.data),):
        raise invalid("mesh", f"cell data {name!r} has shape {labels.shape} on a block of "
                      f"{len(block.data)} tetra, expected one label per cell")
    if labels.dtype.kind == "f":
        whole = whole_numbers(labels)
        if not whole.all():
            raise invalid("mesh", f"cell data {name!r} holds {labels[np.argmin(whole)]}, not a "
                          "whole number")
    elif labels.dtype.kind not in "iub":
        raise invalid("mesh", f"cell data {name!r} has dtype {labels.dtype}, expected integers")
    if len(labels) and (labels.min() < -2**31 or labels.max() >= 2**31):
        raise invalid("mesh", f"cell data {name!r} holds values that do not fit int32")
    return labels.astype(np.int32)


def result_to_meshio(result, label_name="labels", region_names=None):
    """A meshio.Mesh of a RefineResult: one "tetra" block, point data "value", cell data
    "iteration", "quality" and, when the result has labels, `label_name`. region_names
    ({label: name}, TetMesh.region_names) become Gmsh physical volume names (field_data
    {name: [label, 3]}); with label_name "gmsh:physical" the labels are also the elementary
    volumes ("gmsh:geometrical"), as the CLI's .msh writer makes them."""
    import meshio

    # The labels first: formats with one integer per cell (Medit's ref) take meshio's first
    # cell array, and "iteration" written as Medit refs made a refined mesh one region per
    # iteration.
    cell_data = {}
    if result.labels is not None:
        cell_data[label_name] = [result.labels]
        if label_name == "gmsh:physical":
            cell_data["gmsh:geometrical"] = [result.labels]
    cell_data.update({"iteration": [result.iteration], "quality": [result.quality]})
    field_data = {}
    if region_names is not None and not isinstance(region_names, dict):
        raise invalid("region_names", f"expected a dict {{label: name}}, got "
                      f"{type(region_names).__name__}")
    for label, name in (region_names or {}).items():
        # Checked, not coerced: int(1.5), int(True) and int("1") all made label 1.
        if isinstance(label, (bool, np.bool_)) or not isinstance(label, (int, np.integer)):
            raise invalid("region_names", f"label {label!r}: expected an integer label, got "
                          f"{type(label).__name__}")
        if not -2**31 <= int(label) < 2**31:
            raise invalid("region_names", f"label {label}: outside int32, as no label can be")
    for label, name in sorted((int(k), v) for k, v in (region_names or {}).items()):
        if not isinstance(name, str) or not name:
            raise invalid("region_names", f"label {label}: expected a name, got {name!r}")
        # A line break ends the $PhysicalNames line early: neither Gmsh nor meshio read the file
        # back. The CLI's writer refuses the same.
        if any(ord(c) < 32 or ord(c) == 127 for c in name):
            raise invalid("region_names", f"label {label}: the name {name!r} holds a control "
                          "character")
        if name in field_data:
            raise invalid("region_names", f"label {label}: name {name!r} is already label "
                          f"{field_data[name][0]}")
        field_data[name] = np.array([int(label), 3])
    return meshio.Mesh(result.points, [("tetra", result.tets)],
                       point_data={"value": result.values}, cell_data=cell_data,
                       field_data=field_data)
