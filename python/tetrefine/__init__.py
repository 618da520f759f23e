"""tetrefine: refine tetrahedral meshes immersed in voxel volumes on a tetrefine_server.

    import numpy as np, tetrefine
    with tetrefine.Client("localhost:50051") as client:
        result = client.refine(volume, spacing, origin, points, tets, epsilon=0.1)
    result.points, result.tets, result.values, result.iterations, result.stop_reason

Without a server to name, LocalServer runs one for the pipeline (as the CLI embeds it):

    with tetrefine.LocalServer() as server, server.client() as client:
        result = client.refine(volume, spacing, origin, points, tets, epsilon=0.1)

Adapters: volume_from_nibabel, mesh_from_meshio, RefineResult.to_meshio.
Every failure is a TetrefineError carrying the gRPC status code and the server's message.
"""

from tetrefine.adapters import (TetMesh, VolumeGrid, fit_to_volume, mesh_from_meshio,
                                result_to_meshio, volume_from_nibabel)
from tetrefine.client import Client
from tetrefine.errors import TetrefineError
from tetrefine.local_server import LocalServer, find_server_binary
from tetrefine.results import (CONFIGURATIONS, IterationMesh, IterationStats, Record,
                               RefineResult)

__version__ = "0.1.0"

__all__ = [
    "CONFIGURATIONS", "Client", "IterationMesh", "IterationStats", "LocalServer", "Record",
    "RefineResult", "TetMesh", "TetrefineError", "VolumeGrid", "find_server_binary",
    "fit_to_volume", "mesh_from_meshio", "result_to_meshio", "volume_from_nibabel",
]
