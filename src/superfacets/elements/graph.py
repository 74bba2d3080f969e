"""The element graph: elements with geometry, their adjacency, cached per-adjacency data."""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property
from typing import Callable, NamedTuple

import numpy as np

__all__ = ["ElementGraph", "AdjacencyTerms", "as_element_graph", "CHUNK", "chunked"]

#: Adjacencies per chunk when per-adjacency arrays are computed: bounds the
#: temporaries (and fixes the slicing, so every result is the same bit for bit).
CHUNK = 1 << 18


def chunked(n: int, compute: Callable[[slice], np.ndarray], dtype=np.float64) -> np.ndarray:
    """``compute(sl)`` for consecutive slices of ``range(n)``, into one ``(n,)`` array."""
    out = np.empty(n, dtype=dtype)
    for s in range(0, n, CHUNK):
        sl = slice(s, min(n, s + CHUNK))
        out[sl] = compute(sl)
    return out


class AdjacencyTerms(NamedTuple):
    """Geometric terms of the weights, one entry per adjacent pair ``(i, j)``.

    Attributes
    ----------
    geo : (e,) float64 ndarray
        Geodesic term: length of the path between the two elements through
        their shared border (faces: ``|c_i - m_ij| + |m_ij - c_j|``, paper eq. 1).
    cos : (e,) float64 ndarray
        Cosine of the angle between the two normals, clipped to ``[-1, 1]``
        (faces: of the dihedral angle).
    concave : (e,) bool ndarray
        True where the adjacency is concave: ``n_i . (c_j - c_i) > 0``
        (the authors' convexity test), ``i < j``.
    """

    geo: np.ndarray
    cos: np.ndarray
    concave: np.ndarray


@dataclass(frozen=True, eq=False)
class ElementGraph:
    """Elements and their adjacency (for a triangle mesh: the face graph).

    Attributes
    ----------
    kind : str
        What the elements are (``"faces"``).
    positions : (n, 3) float64 ndarray
        Position of each element (faces: centroid).
    sizes : (n,) float64 ndarray
        Size of each element (faces: area), the weight of its position in a
        superfacet's mean and of the metrics.
    normals : (n, 3) float64 ndarray
        Unit normal of each element (zero where undefined).
    centroid : (3,) float64 ndarray
        Reference point of the whole input: the first center is the element
        nearest to it (faces: mean of the referenced vertices, as the authors'
        implementation).
    lower : (3,) float64 ndarray
        Minimum corner of the input's axis-aligned bounding box (origin of the
        grid initialization).
    diagonal : float
        Length of the bounding-box diagonal ``d``.
    pairs : (e, 2) int64 ndarray
        The two elements ``(i, j)``, ``i < j``, of each adjacency, sorted.
    indptr : (n + 1,) int64 ndarray
        CSR row pointers: neighbours of ``f`` are ``indices[indptr[f]:indptr[f + 1]]``.
    indices : (2 e,) int32 ndarray
        CSR column indices (neighbours), ascending within a row.
    dual_edge : (2 e,) int32 or int64 ndarray
        Index into ``pairs`` of each CSR entry: per-adjacency arrays map onto
        CSR as ``values[graph.dual_edge]``.
    lengths : (e,) float64 ndarray
        Length of the border each adjacent pair shares (faces: the mesh edge).
    boundary_elements : (b,) int64 ndarray
        Element of each open border piece (faces: edge used by one face).
    boundary_lengths : (b,) float64 ndarray
        Length of each open border piece.
    edges : (e, 2) int64 ndarray or None
        Faces: the shared mesh edge ``(a, b)``, ``a < b``, of each adjacency.
    boundary_edges : (b, 2) int64 ndarray or None
        Faces: the open-boundary mesh edges, ``a < b``.
    """

    kind: str
    positions: np.ndarray
    sizes: np.ndarray
    normals: np.ndarray
    centroid: np.ndarray
    lower: np.ndarray
    diagonal: float
    pairs: np.ndarray
    indptr: np.ndarray
    indices: np.ndarray
    dual_edge: np.ndarray
    lengths: np.ndarray
    boundary_elements: np.ndarray
    boundary_lengths: np.ndarray
    edges: np.ndarray | None = None
    boundary_edges: np.ndarray | None = None
    terms_of: Callable[[slice], tuple] | None = field(default=None, repr=False)

    @property
    def n_elements(self) -> int:
        """Number of elements ``n``."""
        return int(self.positions.shape[0])

    @property
    def n_edges(self) -> int:
        """Number of adjacent pairs ``e``."""
        return int(self.pairs.shape[0])

    @cached_property
    def area(self) -> float:
        """Total size ``A`` (faces: surface area)."""
        return float(self.sizes.sum())

    @cached_property
    def terms(self) -> AdjacencyTerms:
        """The :class:`AdjacencyTerms` of every adjacency, computed once (in chunks)."""
        e = self.n_edges
        geo, cos = np.empty(e), np.empty(e)
        concave = np.empty(e, dtype=bool)
        for s in range(0, e, CHUNK):
            sl = slice(s, min(e, s + CHUNK))
            geo[sl], cos[sl], concave[sl] = self.terms_of(sl)
        return AdjacencyTerms(geo, cos, concave)

    def to_csr(self, weights: np.ndarray | None = None):
        """The adjacency as a symmetric ``scipy.sparse.csr_array``.

        Parameters
        ----------
        weights : (e,) float ndarray, optional
            Per-adjacency weights; 1 when omitted.
        """
        from scipy.sparse import csr_array

        data = np.ones(self.indices.shape[0]) if weights is None else weights[self.dual_edge]
        n = self.n_elements
        return csr_array((data, self.indices, self.indptr), shape=(n, n))


def as_element_graph(obj) -> ElementGraph:
    """The element graph of ``obj``: itself, or the face graph of a mesh.

    Parameters
    ----------
    obj : ElementGraph, Mesh, trimesh.Trimesh or (vertices, faces)

    Returns
    -------
    ElementGraph

    Raises
    ------
    TypeError, InvalidMeshError
        As :func:`superfacets.mesh.as_mesh`.
    """
    if isinstance(obj, ElementGraph):
        return obj
    from ..mesh import as_mesh

    return as_mesh(obj).graph
