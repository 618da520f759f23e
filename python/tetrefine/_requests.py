"""Checks the caller's numpy arrays and turns them into the Refine request stream.

Everything a caller can get wrong is refused here, before the call starts, with a TetrefineError
(INVALID_ARGUMENT) naming the argument and index; what only the server can judge (a tet outside
the volume, an inverted tet, an epsilon of 0) comes back as the server's INVALID_ARGUMENT.
"""

import numpy as np

from tetrefine.errors import invalid, unsupported

# The wire's voxel types and the little-endian numpy dtype of each.
_WIRE_DTYPES = {
    "VOXEL_TYPE_UINT8": np.dtype("<u1"),
    "VOXEL_TYPE_INT16": np.dtype("<i2"),
    "VOXEL_TYPE_UINT16": np.dtype("<u2"),
    "VOXEL_TYPE_INT32": np.dtype("<i4"),
    "VOXEL_TYPE_FLOAT32": np.dtype("<f4"),
    "VOXEL_TYPE_FLOAT64": np.dtype("<f8"),
}

# Integers up to 2**53 are exact in float64; beyond that a conversion would round silently.
_FLOAT64_EXACT_INTEGER = 2**53


def _wire_voxel_type(volume):
    """(wire type name, little-endian dtype) for a volume's dtype; exact for every value.

    The wire carries uint8, int16, uint16, int32, float32 and float64. Other dtypes travel as the
    smallest of those that holds every value they have (checked on the data for 64-bit and
    unsigned 32-bit integers), so no sample changes: bool and int8 widen, float16 becomes
    float32, int64/uint32/uint64 become int32 when their values fit and float64 otherwise.
    """
    kind, size = volume.dtype.kind, volume.dtype.itemsize
    if kind == "b":
        return "VOXEL_TYPE_UINT8"
    if kind == "u" and size <= 2:
        return "VOXEL_TYPE_UINT8" if size == 1 else "VOXEL_TYPE_UINT16"
    if kind == "i" and size <= 2:
        return "VOXEL_TYPE_INT16"
    if kind == "i" and size == 4:
        return "VOXEL_TYPE_INT32"
    if kind in "iu":
        lo, hi = (int(volume.min()), int(volume.max())) if volume.size else (0, 0)
        if -2**31 <= lo and hi < 2**31:
            return "VOXEL_TYPE_INT32"
        if -_FLOAT64_EXACT_INTEGER <= lo and hi <= _FLOAT64_EXACT_INTEGER:
            return "VOXEL_TYPE_FLOAT64"
        raise invalid("volume", f"{volume.dtype} values up to {max(abs(lo), abs(hi))} do not "
                      "fit int32 and would round in float64; rescale them first")
    if kind == "f":
        if size > 8 and volume.size:
            # longdouble: float64 when that keeps every value, as for the integers.
            finite = volume[np.isfinite(volume)]
            if not np.array_equal(finite.astype(np.float64).astype(volume.dtype), finite):
                raise invalid("volume", f"{volume.dtype} values would round in float64, the "
                              "widest wire type; convert them first")
        return "VOXEL_TYPE_FLOAT64" if size > 4 else "VOXEL_TYPE_FLOAT32"
    raise invalid("volume", f"dtype {volume.dtype} is not a scalar number type; expected "
                  "uint8, int16, uint16, int32, float32, float64 or another integer or float")


def real_number(name, value):
    """`value` as a float: a Python or numpy real number (not bool, not a string)."""
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, float, np.integer,
                                                                       np.floating)):
        raise invalid(name, f"expected a number, got {value!r}")
    return float(value)


def integer(name, value, lo, hi):
    """`value` as an int in [lo, hi]: a Python or numpy integer, or a float holding one."""
    if isinstance(value, (float, np.floating)) and np.isfinite(value) and value == int(value):
        value = int(value)
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, np.integer)):
        raise invalid(name, f"expected a whole number, got {value!r}")
    if not lo <= value <= hi:
        raise invalid(name, f"must be in [{lo}, {hi}], got {value}")
    return int(value)


def flag(name, value):
    """`value` as a bool: True, False (or numpy's), nothing else ("no" is not False)."""
    if not isinstance(value, (bool, np.bool_)):
        raise invalid(name, f"expected True or False, got {value!r}")
    return bool(value)


def whole_numbers(values):
    """Mask of the entries of a float array that are whole numbers below 2**53 (exact in
    float64), so that an integer cast keeps them; inf or 1e20 would wrap."""
    whole = np.isfinite(values) & (np.abs(values) < _FLOAT64_EXACT_INTEGER)
    whole[whole] = values[whole] == np.floor(values[whole])
    return whole


def as_array(name, value):
    """np.asarray(value), refusing ragged nested lists with a message naming the argument, and
    masked arrays: their mask would be dropped without a word (a service sweep)."""
    if isinstance(value, np.ma.MaskedArray):
        raise invalid(name, "a masked array: its mask cannot be sent; fill the masked entries "
                      "first (e.g. value.filled(0))")
    try:
        array = np.asarray(value)
    except (TypeError, ValueError) as error:
        raise invalid(name, f"not an array of numbers ({error})") from None
    if array.dtype == object and array.ndim == 0:
        # An object where an array goes (a nibabel image, a VolumeGrid, a meshio mesh) read as
        # "got shape ()" (an outside review): name what came and what to pass.
        hints = {"Nifti1Image": "volume_from_nibabel(image) gives the array as .data",
                 "Nifti2Image": "volume_from_nibabel(image) gives the array as .data",
                 "VolumeGrid": "pass grid.data, grid.spacing and grid.origin",
                 "TetMesh": "pass mesh.points and mesh.tets",
                 "Mesh": "mesh_from_meshio(mesh) gives .points and .tets"}
        kind = type(value).__name__
        hint = hints.get(kind)
        raise invalid(name, f"expected an array of numbers, got a {kind}"
                      + (f" ({hint})" if hint else ""))
    return array


def _vector3(name, value, positive=False):
    if np.iscomplexobj(value):
        raise invalid(name, f"expected 3 real numbers, got {value!r}")
    try:
        v = np.asarray(value, dtype=np.float64).reshape(-1)
    except (TypeError, ValueError):
        raise invalid(name, f"expected 3 numbers, got {value!r}") from None
    if v.shape != (3,):
        raise invalid(name, f"expected 3 numbers, got {v.size}")
    if not np.all(np.isfinite(v)):
        raise invalid(name, f"must be finite, got {v.tolist()}")
    if positive and not np.all(v > 0):
        axis = int(np.argmin(v > 0))
        raise invalid(name, f"must be > 0 on every axis, got {v[axis]} on axis {'xyz'[axis]}")
    return [float(x) for x in v]


class Inputs:
    """The checked, wire-ready form of one refine() call's arrays.

    volume_bytes: the samples, little-endian, x fastest then y then z.
    dims: samples per axis (x, y, z). points: (n, 3) float64. tets: (m, 4) uint32.
    labels: (m,) int32 or None. direction: 9 floats row-major, or None for the identity.
    """

    def __init__(self, volume, spacing, origin, points, tets, direction=None, labels=None):
        volume = as_array("volume", volume)
        if volume.ndim != 3:
            raise invalid("volume", f"expected a 3-d array indexed [x, y, z], got shape "
                          f"{volume.shape}")
        if min(volume.shape) < 2:
            raise invalid("volume", f"every axis needs at least 2 samples, got shape "
                          f"{volume.shape}")
        self.voxel_type = _wire_voxel_type(volume)
        # order="F": element [x, y, z] at offset x + nx * (y + ny * z), the wire's order,
        # whatever the array's own memory layout (C, Fortran or a strided view).
        self.volume_bytes = volume.astype(_WIRE_DTYPES[self.voxel_type],
                                          copy=False).tobytes(order="F")
        self.dims = tuple(int(n) for n in volume.shape)
        self.spacing = _vector3("spacing", spacing, positive=True)
        self.origin = _vector3("origin", origin)
        self.direction = _direction(direction)

        points = as_array("points", points)
        if points.ndim != 2 or points.shape[1] != 3:
            raise invalid("points", f"expected shape (n, 3), got {points.shape}")
        if points.dtype.kind not in "iuf":
            raise invalid("points", f"expected numbers, got dtype {points.dtype}")
        self.points = np.ascontiguousarray(points, dtype=np.float64)
        bad = ~np.isfinite(self.points).all(axis=1)
        if bad.any():
            raise invalid("points", f"vertex {int(np.argmax(bad))} is not finite: "
                          f"{self.points[np.argmax(bad)].tolist()}")
        n = len(self.points)
        if n >= 2**32:
            raise invalid("points", f"{n} vertices; tet indices on the wire are 32-bit")

        tets = as_array("tets", tets)
        if tets.ndim != 2 or tets.shape[1] != 4:
            raise invalid("tets", f"expected shape (m, 4), got {tets.shape}")
        if tets.dtype.kind not in "iu":
            if tets.dtype.kind != "f":
                raise invalid("tets", f"expected integer vertex indices, got dtype {tets.dtype}")
            # Float indices are taken when they are whole numbers.
            whole = whole_numbers(tets)
            if not whole.all():
                t, corner = np.argwhere(~whole)[0]
                raise invalid("tets", f"tet {t} corner {corner} is {tets[t, corner]}, not a "
                              "vertex index")
            tets = tets.astype(np.int64)
        if len(tets):
            out_of_range = (tets < 0) | (tets >= n)
            if out_of_range.any():
                t, corner = np.argwhere(out_of_range)[0]
                raise invalid("tets", f"tet {t} corner {corner} is vertex {int(tets[t, corner])},"
                              f" not in [0, {n})")
        self.tets = np.ascontiguousarray(tets, dtype=np.uint32)

        self.labels = None
        if labels is not None:
            labels = as_array("labels", labels)
            if labels.shape != (len(self.tets),):
                raise invalid("labels", f"expected one label per tet, shape ({len(self.tets)},),"
                              f" got {labels.shape}")
            if labels.dtype.kind not in "iub":
                raise invalid("labels", f"expected integers, got dtype {labels.dtype}")
            if len(labels) and (labels.min() < -2**31 or labels.max() >= 2**31):
                raise invalid("labels", "values must fit int32")
            self.labels = labels.astype(np.int32)


def _direction(direction):
    """9 floats row-major, or None when `direction` is None or the identity."""
    if direction is None:
        return None
    if np.iscomplexobj(direction):
        raise invalid("direction", "expected real numbers, got complex ones")
    try:
        d = np.asarray(direction, dtype=np.float64)
    except (TypeError, ValueError):
        raise invalid("direction", f"expected a 3x3 matrix, got {direction!r}") from None
    if d.size != 9:
        raise invalid("direction", f"expected a 3x3 matrix (9 numbers), got shape {d.shape}")
    d = d.reshape(3, 3)
    if not np.all(np.isfinite(d)):
        raise invalid("direction", "must be finite")
    # Unit columns, as the server requires (wire/request_reader.cc says why): a direction taken
    # straight from an affine would scale the volume a second time.
    lengths = np.sqrt((d * d).sum(axis=0))
    for column, length in enumerate(lengths):
        if not abs(length - 1.0) <= 1e-3:
            raise invalid("direction", f"column {column} has length {length:g}; the columns are "
                          "unit vectors and the voxel size goes in spacing (from an affine: "
                          "affine[:3, :3] / spacing)")
    if np.array_equal(d, np.eye(3)):
        return None
    return [float(x) for x in d.reshape(-1)]


def build_options(pb, protocol, epsilon, *, max_iterations=None, max_tets=None, scheme=None,
                  certify=False, norm_coeff=None, clamp=False, fix_orientation=False,
                  track_parents=False, quality_reference=None, lattice_n=None,
                  lattice_max_tets=None, lattice_seed=None, min_edge_length=None,
                  min_quality=None):
    """The RefineOptions message; an unset argument leaves the server's default."""
    # Types are checked here (a string epsilon, a float iteration count, certify="no" were
    # coerced or raised numpy's and protobuf's own exceptions); ranges are the server's.
    options = pb.RefineOptions(epsilon=real_number("epsilon", epsilon))
    if max_iterations is not None:
        options.max_iterations = integer("max_iterations", max_iterations, 0, 2**31 - 1)
    if max_tets is not None:
        options.max_tets = integer("max_tets", max_tets, 1, 2**63 - 1)
    if norm_coeff is not None:
        options.norm_coeff = real_number("norm_coeff", norm_coeff)
    # What the CLI's --lattice-n, --lattice-max-tets, --lattice-seed, --min-edge-length and
    # --min-quality set (a service sweep could not reproduce such CLI runs from Python).
    if lattice_n is not None:
        # The core's bound; a server's --max_lattice_n may be lower and says so.
        options.lattice_n = integer("lattice_n", lattice_n, 0, 64)
    if lattice_max_tets is not None:
        options.lattice_max_tets = integer("lattice_max_tets", lattice_max_tets, 0, 2**63 - 1)
    if lattice_seed is not None:
        options.lattice_seed = integer("lattice_seed", lattice_seed, 0, 2**64 - 1)
    if min_edge_length is not None:
        options.min_edge_length = real_number("min_edge_length", min_edge_length)
    if min_quality is not None:
        options.min_quality = real_number("min_quality", min_quality)
    certify = flag("certify", certify)
    track_parents = flag("track_parents", track_parents)
    if flag("clamp", clamp):
        options.outside_policy = pb.OUTSIDE_POLICY_CLAMP
    if flag("fix_orientation", fix_orientation):
        options.orientation_policy = pb.ORIENTATION_POLICY_NORMALIZE
    if scheme is not None:
        if protocol.scheme_field is None:
            raise unsupported("scheme", "RefineOptions.scheme field")
        value = protocol.scheme_value(str(scheme))
        if value is None:
            raise invalid("scheme", f"unknown scheme {scheme!r}; this protocol knows "
                          f"{', '.join(protocol.scheme_names())}")
        setattr(options, "scheme", value)
    if certify:
        if protocol.certify_field is None:
            raise unsupported("certify", "RefineOptions.certify field")
        setattr(options, "certify", True)
    if track_parents:
        if "track_parents" not in pb.RefineOptions.DESCRIPTOR.fields_by_name:
            raise unsupported("track_parents", "RefineOptions.track_parents field")
        setattr(options, "track_parents", True)
    if quality_reference is not None:
        if "quality_reference" not in pb.RefineOptions.DESCRIPTOR.fields_by_name:
            raise unsupported("quality_reference", "RefineOptions.quality_reference field")
        setattr(options, "quality_reference", real_number("quality_reference", quality_reference))
    return options


def check_features(protocol, inputs):
    """Raises UNIMPLEMENTED for an input the protocol cannot carry."""
    if inputs.direction is not None and protocol.direction_field is None:
        what = ("VolumeHeader.direction as 9 doubles" if protocol.direction_misshapen else
                "VolumeHeader.direction field")
        raise unsupported("direction", f"{what}; only the identity can be sent")
    if inputs.labels is not None and protocol.request_labels is None:
        raise unsupported("labels", "label chunk in RefineRequest")


def _per_chunk(chunk_bytes, element_bytes):
    return max(1, chunk_bytes // element_bytes)


def _label_wire_bytes(labels):
    """Bytes a label of `labels` can take as a varint int32: 1 to 5, or 10 if one is negative.

    Sized at 4 bytes a label, negative labels overran a server's --max_message_bytes (as the
    C++ writer's wire::LabelWireBytes says)."""
    if len(labels) == 0:
        return 1
    if int(labels.min()) < 0:
        return 10
    return max(1, (int(labels.max()).bit_length() + 6) // 7)


def requests(pb, protocol, options, inputs, chunk_bytes):
    """Yields the Refine request stream: options, volume, mesh in chunks, end of input."""
    yield pb.RefineRequest(options=options)

    nx, ny, nz = inputs.dims
    header = pb.VolumeHeader(
        dims=pb.GridIndex(x=nx, y=ny, z=nz),
        origin=pb.Vector3(x=inputs.origin[0], y=inputs.origin[1], z=inputs.origin[2]),
        spacing=pb.Vector3(x=inputs.spacing[0], y=inputs.spacing[1], z=inputs.spacing[2]),
        voxel_type=pb.VoxelType.Value(inputs.voxel_type),
        total_bytes=len(inputs.volume_bytes))
    if inputs.direction is not None:
        getattr(header, protocol.direction_field.name).extend(inputs.direction)
    yield pb.RefineRequest(volume_header=header)
    data = memoryview(inputs.volume_bytes)
    for offset in range(0, len(data), chunk_bytes):
        yield pb.RefineRequest(volume_chunk=pb.VolumeChunk(
            offset=offset, data=bytes(data[offset:offset + chunk_bytes])))

    mesh_header = pb.MeshHeader(vertex_count=len(inputs.points), tet_count=len(inputs.tets))
    if inputs.labels is not None:
        if protocol.mesh_header_has_labels:
            setattr(mesh_header, "has_labels", True)
        if protocol.mesh_header_label_count is not None:
            setattr(mesh_header, protocol.mesh_header_label_count, len(inputs.labels))
    yield pb.RefineRequest(mesh_header=mesh_header)
    step = _per_chunk(chunk_bytes, 24)
    for start in range(0, len(inputs.points), step):
        yield pb.RefineRequest(vertex_chunk=pb.VertexChunk(
            start_index=start, coordinates=inputs.points[start:start + step].ravel().tolist()))
    step = _per_chunk(chunk_bytes, 16)
    for start in range(0, len(inputs.tets), step):
        yield pb.RefineRequest(tet_chunk=pb.TetChunk(
            start_index=start, indices=inputs.tets[start:start + step].ravel().tolist()))
    if inputs.labels is not None:
        kind = protocol.request_labels
        step = _per_chunk(chunk_bytes, _label_wire_bytes(inputs.labels))
        for start in range(0, len(inputs.labels), step):
            request = pb.RefineRequest()
            chunk = getattr(request, kind.name)
            chunk.start_index = start
            getattr(chunk, kind.values).extend(inputs.labels[start:start + step].tolist())
            yield request
    yield pb.RefineRequest(end_of_input=pb.EndOfInput())
