"""superfacets: fast and scalable mesh superfacets.

An implementation of G. Simari, G. Picciau, L. De Floriani, "Fast and
Scalable Mesh Superfacets", Computer Graphics Forum 33(7), 2014: over-segment
a triangle mesh into compact patches whose borders follow concavities.

>>> from superfacets import read_mesh, superfacets      # doctest: +SKIP
>>> mesh = read_mesh("horse.tri.xz")                    # doctest: +SKIP
>>> labels = superfacets(mesh, n_segments=150, alpha=200)  # doctest: +SKIP
"""

from . import _warmup

_warmup.start()  # numba's process start-up, overlapped with the imports below

from .connectivity import enforce_connectivity  # noqa: E402
from .errors import (InvalidMeshError, MemoryLimitError, MeshFormatError, ParameterError,
                     SuperfacetsError)
from .graph import FaceGraph, paper_weights, shlafman_weights
from .io import read_labels, read_mesh, write_colored_mesh, write_labels, write_mesh
from .mesh import Mesh, as_mesh
from .segment import SegmentationResult, segment, superfacets

__version__ = "0.1.0"

__all__ = [
    "FaceGraph",
    "InvalidMeshError",
    "MemoryLimitError",
    "Mesh",
    "MeshFormatError",
    "ParameterError",
    "SegmentationResult",
    "SuperfacetsError",
    "as_mesh",
    "enforce_connectivity",
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
