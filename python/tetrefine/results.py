"""What refine() returns: the refined mesh as numpy arrays and the statistics as plain records."""

import numpy as np
from google.protobuf import descriptor as _descriptor

# IterationStats.configuration_counts order (the paper's Table 1 configurations).
CONFIGURATIONS = ("0", "1", "2a", "2b", "3a", "3b", "3c", "4a", "4b", "5", "6")


class Record:
    """A protobuf message as plain Python values: attributes named like the proto's fields.

    Built from the message descriptor, so fields added to the protocol appear without a change
    here. Nested messages are Records, repeated fields lists, enums their value name in lower
    case without the enum's prefix (STOP_REASON_CONVERGED -> "converged").
    """

    def __init__(self, **fields):
        self.__dict__.update(fields)

    @classmethod
    def from_message(cls, message):
        fields = {}
        for field in message.DESCRIPTOR.fields:
            value = getattr(message, field.name)
            repeated = field.label == _descriptor.FieldDescriptor.LABEL_REPEATED
            if field.message_type is not None:
                # Nested messages are plain Records: a subclass's own fields and properties
                # (IterationStats.configurations) would not apply to them.
                value = ([Record.from_message(v) for v in value] if repeated else
                         Record.from_message(value))
            elif field.enum_type is not None:
                value = ([_enum_name(field.enum_type, v) for v in value] if repeated else
                         _enum_name(field.enum_type, value))
            elif repeated:
                value = list(value)
            fields[field.name] = value
        return cls(**fields)

    def as_dict(self):
        """The record as nested dicts and lists (e.g. for json.dump)."""
        def plain(v):
            if isinstance(v, Record):
                return v.as_dict()
            if isinstance(v, list):
                return [plain(x) for x in v]
            return v
        return {k: plain(v) for k, v in self.__dict__.items()}

    def __eq__(self, other):
        return isinstance(other, Record) and self.__dict__ == other.__dict__

    def __repr__(self):
        inner = ", ".join(f"{k}={v!r}" for k, v in self.__dict__.items())
        return f"{type(self).__name__}({inner})"


def _enum_name(enum_type, number):
    value = enum_type.values_by_number.get(number)
    if value is None:
        return number
    prefix = "".join("_" + c if c.isupper() and i else c for i, c in enumerate(enum_type.name))
    prefix = prefix.upper() + "_"
    name = value.name[len(prefix):] if value.name.startswith(prefix) else value.name
    return name.lower()


class IterationStats(Record):
    """One iteration's statistics, as the paper's tables report them (see IterationStats in
    tetrefine.proto): iteration (1-based), initial_tets (INT), final_tets (FNT), tets_with_error
    (NTwE), edges, split_edges, short_edges_kept, max_error and mean_error (relative, at the start
    of the iteration), configuration_counts (11 counts in CONFIGURATIONS order),
    schonhardt_prisms, quality (min, mean, count after the iteration), seconds; for the
    longest-edge scheme also max_segment_error (certified runs only), closure_edges,
    guard_edges, failing_tets and other_tilings (tets cut by a better tiling of their faces
    than the paper's table)."""

    @property
    def configurations(self):
        """Tets by configuration as a dict keyed "0", "1", "2a", ... "6"."""
        return dict(zip(CONFIGURATIONS, self.configuration_counts))


class IterationMesh:
    """The mesh an iteration produced, as refine(on_mesh=...) streams it.

    iteration: the iteration that produced it (1-based).
    points:    (n, 3) float64 world coordinates.
    tets:      (m, 4) int64 vertex indices, positively oriented.
    values:    (n,) float64, the volume's trilinear value at each vertex.
    labels:    (m,) int32 per-tet labels inherited from the input tets, or None when the call
               sent no labels.
    The final mesh is the RefineResult; its per-tet iteration, quality and parent arrays are
    only there.
    """

    def __init__(self, iteration, points, tets, values, labels):
        self.iteration = iteration
        self.points = points
        self.tets = tets
        self.values = values
        self.labels = labels

    def __repr__(self):
        return (f"IterationMesh(iteration {self.iteration}: {len(self.points)} vertices, "
                f"{len(self.tets)} tets)")


class RefineResult:
    """The refined mesh and how the refinement went.

    points:     (n, 3) float64 world coordinates.
    tets:       (m, 4) int64 vertex indices, positively oriented.
    values:     (n,) float64, the volume's trilinear value at each vertex.
    iteration:  (m,) int32, the iteration that created each tet (0: an input tet).
    quality:    (m,) float32, mean-ratio quality of each tet (1 regular, towards 0 flat).
    labels:     (m,) int32 per-tet labels inherited from the input tets, or None when the call
                sent no labels.
    parent:     (m,) int64 index of the input tet each tet lies in (track_parents=True), else
                None.
    certified_max_error: certify=True and converged: the largest lattice error over every tet
                (<= epsilon); else None.
    iterations: list of IterationStats, one per completed iteration.
    stop_reason: "converged", "max_iterations", "tet_budget", "cancelled", "quality_floor" or
                "min_edge_length" (every edge above epsilon is shorter than min_edge_length:
                none was split, and summary.final_max_error is above epsilon).
    lattice:    Record of the error sampled on the barycentric lattice inside the tets (n,
                tets_sampled, points_sampled, max_error, mean_error, share_above_epsilon, and
                volume_mean_error, volume_share_above_epsilon: each tet's points weighed by its
                volume, the figures to judge a result by; see the README).
                With lattice_n=0 no check runs: n and tets_sampled are 0, and its errors (0)
                are not measurements.
    summary:    Record of the whole Summary message (norm_coeff, initial_quality, final_quality,
                final_max_error, timings, ...), as the wire has it: its certified_max_error is
                -1 where certified_max_error above is None.
    """

    def __init__(self, points, tets, values, iteration, quality, labels, iterations, summary,
                 parent=None):
        self.points = points
        self.tets = tets
        self.values = values
        self.iteration = iteration
        self.quality = quality
        self.labels = labels
        self.parent = parent
        certified = getattr(summary, "certified_max_error", -1.0)
        self.certified_max_error = certified if certified is not None and certified >= 0 else None
        self.iterations = iterations
        self.summary = summary
        self.stop_reason = summary.stop_reason
        self.lattice = summary.lattice

    def to_meshio(self, label_name="labels", region_names=None):
        """A meshio.Mesh: point data "value", cell data "iteration" and "quality" (and
        `label_name` when the result has labels); region_names ({label: name}) as Gmsh
        physical names. For the input's own: to_meshio(mesh.label_name or "labels",
        mesh.region_names) with `mesh` from mesh_from_meshio. Needs the meshio package."""
        from tetrefine.adapters import result_to_meshio
        return result_to_meshio(self, label_name=label_name, region_names=region_names)

    def __repr__(self):
        return (f"RefineResult({len(self.points)} vertices, {len(self.tets)} tets, "
                f"{len(self.iterations)} iterations, stop_reason={self.stop_reason!r})")
