"""superfacets: fast and scalable mesh superfacets.

An implementation of G. Simari, G. Picciau, L. De Floriani, "Fast and
Scalable Mesh Superfacets", Computer Graphics Forum 33(7), 2014: over-segment
a triangle mesh into compact patches whose borders follow concavities.
Importing the package does no work beyond the imports.

>>> from superfacets import read_mesh, superfacets      # doctest: +SKIP
>>> mesh = read_mesh("horse.tri.xz")                    # doctest: +SKIP
>>> labels = superfacets(mesh, n_segments=150, alpha=200)  # doctest: +SKIP
"""

from .connectivity import enforce_connectivity
from .elements import ElementGraph, face_graph
from .errors import (InvalidMeshError, MemoryLimitError, MeshFormatError, ParameterError,
                     SuperfacetsError)
from .io import read_labels, read_mesh, write_colored_mesh, write_labels, write_mesh
from .mesh import Mesh, as_mesh
from .params import DEFAULTS, SegmentParams
from .segment import SegmentationResult, segment, superfacets
from .weights import edge_weights, paper_weights, shlafman_weights

__version__ = "0.1.0"

__all__ = [
    "DEFAULTS",
    "ElementGraph",
    "InvalidMeshError",
    "MemoryLimitError",
    "Mesh",
    "MeshFormatError",
    "ParameterError",
    "SegmentParams",
    "SegmentationResult",
    "SuperfacetsError",
    "as_mesh",
    "edge_weights",
    "enforce_connectivity",
    "face_graph",
    "paper_weights",
    "read_labels",
    "read_mesh",
    "segment",
    "shlafman_weights",
    "superfacets",
    "write_colored_mesh",
    "write_labels",
    "write_mesh",
]
