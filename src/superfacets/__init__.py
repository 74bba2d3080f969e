"""superfacets: fast and scalable mesh superfacets.

An implementation of G. Simari, G. Picciau, L. De Floriani, "Fast and
Scalable Mesh Superfacets", Computer Graphics Forum 33(7), 2014: over-segment
a triangle mesh into compact patches whose borders follow concavities; and
the same method on mesh vertices and point clouds (superpoints).

Importing the package does no work: each public name below is imported from
its module on first use (so ``superfacets --help`` never loads numba).

>>> from superfacets import read_mesh, superfacets      # doctest: +SKIP
>>> mesh = read_mesh("horse.tri.xz")                    # doctest: +SKIP
>>> labels = superfacets(mesh, n_segments=150, alpha=200)  # doctest: +SKIP
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING

from ._version import __version__  # noqa: F401 (the package's version)

#: Public name -> the module that defines it.
_PUBLIC = {
    "DEFAULTS": "method.params",
    "SegmentParams": "method.params",
    "ElementGraph": "elements",
    "face_graph": "elements",
    "InvalidMeshError": "errors",
    "MemoryLimitError": "errors",
    "MeshFormatError": "errors",
    "ParameterError": "errors",
    "SuperfacetsError": "errors",
    "MissingExtraError": "errors",
    "Mesh": "inputs.mesh",
    "as_mesh": "inputs.convert",
    "read_mesh": "io",
    "write_mesh": "io",
    "read_labels": "io",
    "write_labels": "io",
    "write_colored_mesh": "io",
    "segment": "api.segmentation",
    "superfacets": "api.segmentation",
    "superpoints": "api.segmentation",
    "adaptive_superpoints": "api.levels",
    "PointCloud": "inputs.cloud",
    "as_cloud": "inputs.cloud",
    "InvalidCloudError": "inputs.cloud",
    "read_cloud": "io",
    "read_input": "io",
    "write_segindices": "io",
    "SegmentationResult": "api.segmentation",
    "enforce_connectivity": "method.connectivity",
    "edge_weights": "method.weights",
    "paper_weights": "method.weights",
    "shlafman_weights": "method.weights",
    "TetMesh": "inputs.tetmesh",
    "read_volume": "io",
    "write_volume_labels": "io",
    "segment_tiled": "scale.tiles.run",
    "TiledResult": "api.result",
    "NotebookView": "viz.html",
}

__all__ = [
    "DEFAULTS",
    "ElementGraph",
    "InvalidCloudError",
    "InvalidMeshError",
    "MemoryLimitError",
    "Mesh",
    "MeshFormatError",
    "PointCloud",
    "MissingExtraError",
    "NotebookView",
    "ParameterError",
    "SegmentParams",
    "SegmentationResult",
    "SuperfacetsError",
    "TetMesh",
    "TiledResult",
    "adaptive_superpoints",
    "as_cloud",
    "as_mesh",
    "edge_weights",
    "enforce_connectivity",
    "face_graph",
    "paper_weights",
    "read_cloud",
    "read_input",
    "read_labels",
    "read_mesh",
    "read_volume",
    "segment",
    "segment_tiled",
    "shlafman_weights",
    "superfacets",
    "superpoints",
    "write_colored_mesh",
    "write_labels",
    "write_mesh",
    "write_segindices",
    "write_volume_labels",
]


def __getattr__(name: str):
    module = _PUBLIC.get(name)
    if module is None:
        raise AttributeError(f"module 'superfacets' has no attribute {name!r}")
    value = getattr(importlib.import_module(f".{module}", __name__), name)
    globals()[name] = value  # the next access is a plain lookup
    return value


def __dir__():  # the public names (and the module's own dunders), not its imports' helpers
    return sorted(set(__all__) | {n for n in globals() if n.startswith("__")})


if TYPE_CHECKING:  # the same names, for type checkers and IDEs
    from .api.levels import adaptive_superpoints
    from .api.segmentation import SegmentationResult, segment, superfacets, superpoints
    from .elements import ElementGraph, face_graph
    from .errors import (
        InvalidMeshError,
        MemoryLimitError,
        MeshFormatError,
        MissingExtraError,
        ParameterError,
        SuperfacetsError,
    )
    from .inputs.cloud import InvalidCloudError, PointCloud, as_cloud
    from .inputs.convert import as_mesh
    from .inputs.mesh import Mesh
    from .inputs.tetmesh import TetMesh
    from .io import (
        read_cloud,
        read_input,
        read_labels,
        read_mesh,
        read_volume,
        write_colored_mesh,
        write_labels,
        write_mesh,
        write_segindices,
        write_volume_labels,
    )
    from .method.connectivity import enforce_connectivity
    from .method.params import DEFAULTS, SegmentParams
    from .method.weights import edge_weights, paper_weights, shlafman_weights
    from .scale.tiles.run import TiledResult, segment_tiled
