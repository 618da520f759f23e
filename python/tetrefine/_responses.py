"""Reassembles the Refine response stream into a RefineResult."""

import grpc
import numpy as np

from tetrefine.errors import TetrefineError
from tetrefine.results import IterationMesh, IterationStats, Record, RefineResult

# Response chunk kind -> (its repeated field, numpy dtype, values per element, mesh array name).
_CHUNKS = {
    "vertex_chunk": ("coordinates", np.float64, 3, "points"),
    "value_chunk": ("values", np.float64, 1, "values"),
    "tet_chunk": ("indices", np.uint32, 4, "tets"),
    "tet_iteration_chunk": ("iterations", np.int32, 1, "iteration"),
    "tet_quality_chunk": ("qualities", np.float32, 1, "quality"),
    "tet_parent_chunk": ("parents", np.uint32, 1, "parent"),
}


def _broken(message):
    # The server broke its own protocol: not the caller's fault, and not retryable as is.
    return TetrefineError(grpc.StatusCode.INTERNAL, f"malformed response from the server: "
                          f"{message}")


class _MeshParts:
    """Arrays of one announced mesh, filled chunk by chunk in order."""

    def __init__(self, header, label_kind):
        self.final = header.final
        self.iteration = header.iteration
        self.label_count = header.tet_label_count
        self.sizes = {
            "points": header.vertex_count, "values": header.value_count,
            "tets": header.tet_count, "iteration": header.tet_iteration_count,
            "quality": header.tet_quality_count,
            # A protocol without parents announces none.
            "parent": getattr(header, "tet_parent_count", 0),
        }
        self.arrays = {name: [] for name in self.sizes}
        self.filled = {name: 0 for name in self.sizes}
        self.label_kind = label_kind
        self.labels, self.labels_filled = [], 0

    def add(self, kind, chunk):
        if self.label_kind is not None and kind == self.label_kind.name:
            data = np.asarray(getattr(chunk, self.label_kind.values), dtype=np.int32)
            if chunk.start_index != self.labels_filled:
                raise _broken(f"{kind} start_index {chunk.start_index}, expected "
                              f"{self.labels_filled}")
            self.labels.append(data)
            self.labels_filled += len(data)
            return
        field, dtype, width, name = _CHUNKS[kind]
        data = np.asarray(getattr(chunk, field), dtype=dtype)
        if chunk.start_index != self.filled[name]:
            raise _broken(f"{kind} start_index {chunk.start_index}, expected {self.filled[name]}")
        if len(data) % width:
            raise _broken(f"{kind} of {len(data)} values, not a multiple of {width}")
        self.arrays[name].append(data)
        self.filled[name] += len(data) // width
        if self.filled[name] > self.sizes[name]:
            raise _broken(f"more {name} than the mesh header's {self.sizes[name]}")

    def complete(self):
        """Whether every announced element has arrived."""
        return (self.filled == self.sizes and
                (self.label_kind is None or self.labels_filled == self.label_count))

    def finish(self):
        for name, size in self.sizes.items():
            if self.filled[name] != size:
                raise _broken(f"{self.filled[name]} {name} of the {size} announced")
        out = {}
        for _, dtype, width, name in _CHUNKS.values():
            parts = self.arrays[name]
            flat = np.concatenate(parts) if parts else np.zeros(0, dtype=dtype)
            out[name] = flat.reshape(-1, width) if width > 1 else flat
        out["labels"] = np.concatenate(self.labels) if self.labels else None
        return out


class CallbackRaised(Exception):
    """What on_iteration or on_mesh raised, carried out of the response loop as it was, so that
    the client cancels the call and re-raises it: a grpc.RpcError a callback raised (a call to
    another service that failed) was taken for this call's own failure, reported as the
    tetrefine server's status, and the call was left running on the server."""

    def __init__(self, error):
        super().__init__(error)
        self.error = error


def _call_back(callback, argument):
    try:
        callback(argument)
    except Exception as error:
        raise CallbackRaised(error) from None


class ResponseReader:
    """Feed responses in order with add(); result() once the stream has ended."""

    def __init__(self, protocol, on_iteration=None, on_mesh=None, labels_sent=False):
        self.protocol = protocol
        self.on_iteration = on_iteration
        self.on_mesh = on_mesh
        self.labels_sent = labels_sent
        self.iterations = []
        self.mesh = None
        self.final = None
        self.summary = None

    def add(self, response):
        kind = response.WhichOneof("kind")
        if kind == "iteration_stats":
            stats = IterationStats.from_message(response.iteration_stats)
            self.iterations.append(stats)
            if self.on_iteration is not None:
                _call_back(self.on_iteration, stats)
        elif kind == "mesh_header":
            if self.mesh is not None and self.mesh.final:
                raise _broken("a mesh header after the final mesh")
            if self.mesh is not None and not self.mesh.complete():
                self.mesh.finish()  # raises, naming what is missing
            self.mesh = _MeshParts(response.mesh_header, self.protocol.response_labels)
            self._deliver_if_complete()
        elif kind == "summary":
            self.summary = Record.from_message(response.summary)
        elif kind is None:
            raise _broken("a response with no kind set")
        else:
            if self.mesh is None:
                raise _broken(f"{kind} before any mesh header")
            self.mesh.add(kind, getattr(response, kind))
            self._deliver_if_complete()

    def _deliver_if_complete(self):
        # An intermediate mesh goes to on_mesh as soon as its last chunk has arrived, and is
        # not kept: a long run streams many.
        mesh = self.mesh
        if mesh.final or not mesh.complete():
            return
        arrays = mesh.finish()
        self.mesh = None
        if self.on_mesh is not None:
            labels = arrays["labels"] if self.labels_sent else None
            if self.labels_sent and (labels is None or len(labels) != len(arrays["tets"])):
                raise _broken(f"labels were sent, but {0 if labels is None else len(labels)} "
                              f"came back for the {len(arrays['tets'])} tets of iteration "
                              f"{mesh.iteration}'s mesh")
            _call_back(self.on_mesh, IterationMesh(mesh.iteration, arrays["points"],
                                                   arrays["tets"].astype(np.int64),
                                                   arrays["values"], labels))

    def result(self, labels_sent):
        if self.summary is None:
            raise _broken("the stream ended without a summary")
        if self.mesh is None or not self.mesh.final:
            raise _broken("the stream ended without the final mesh")
        mesh = self.mesh.finish()
        labels = mesh["labels"]
        if labels_sent:
            if labels is None or len(labels) != len(mesh["tets"]):
                raise _broken(f"labels were sent, but {0 if labels is None else len(labels)} "
                              f"came back for {len(mesh['tets'])} tets")
        else:
            labels = None
        return RefineResult(
            points=mesh["points"], tets=mesh["tets"].astype(np.int64), values=mesh["values"],
            iteration=mesh["iteration"], quality=mesh["quality"], labels=labels,
            iterations=self.iterations, summary=self.summary,
            parent=mesh["parent"].astype(np.int64) if len(mesh["parent"]) else None)
