"""The element graph: elements with geometry, their adjacency, cached per-adjacency data."""

from __future__ import annotations

from dataclasses import dataclass, field, fields
from functools import cached_property
from typing import Callable, Mapping, NamedTuple

import numpy as np

from .._kernels import native
from .._runtime import threads
from .._runtime.threads import split
from .kinds import KINDS

__all__ = ["ElementGraph", "AdjacencyTerms", "adjacency_csr", "CHUNK",
           "chunked", "pairs_from_csr", "LAZY"]

#: Adjacencies per chunk when per-adjacency arrays are computed: bounds the
#: temporaries (and fixes the slicing, so every result is the same bit for bit).
CHUNK = 1 << 18

#: CSR entries (twice the adjacencies) from which adjacency numbers are int64: int32
#: below, 4 bytes less per entry (the tests lower it to run the int64 layouts)
WIDE_ENTRIES = 2**31 - 1


def adjacency_dtype(n_entries: int) -> type:
    """The dtype of adjacency numbers (``dual_edge``) for a CSR of ``n_entries``."""
    return np.int32 if n_entries < WIDE_ENTRIES else np.int64


def chunked(n: int, compute: Callable[[slice], np.ndarray], dtype=np.float64) -> np.ndarray:
    """``compute(sl)`` for consecutive slices of ``range(n)`` (:data:`CHUNK` long), into
    one ``(n,)`` array: ranges of slices on threads, the same slices for any number of
    threads, so the same result. ``compute`` runs on several threads at once: it may
    only read what its caller made before (no cached property computed on first use)."""

    out = np.empty(n, dtype=dtype)

    def part(c0: int, c1: int) -> None:
        for s in range(c0 * CHUNK, min(n, c1 * CHUNK), CHUNK):
            sl = slice(s, min(n, s + CHUNK))
            out[sl] = compute(sl)

    threads.run_ranges(part, split(-(-n // CHUNK), min_per_thread=1))
    return out


def adjacency_csr(lo: np.ndarray, hi: np.ndarray, n: int
                  ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The symmetric CSR layout of ``e`` adjacent pairs ``(lo[t], hi[t])`` of ``n`` elements.

    Parameters
    ----------
    lo, hi : (e,) int ndarray
        The two elements of each adjacency (one entry per pair, no repeats).
    n : int
        Number of elements.

    Returns
    -------
    indptr : (n + 1,) int64 ndarray
    indices : (2 e,) int32 ndarray
        Neighbours, ascending within each row.
    dual_edge : (2 e,) int32 ndarray (int64 beyond 2**31 entries)
        The pair ``t`` of each CSR entry.
    """

    csr_of_pairs = native.kernel("adjacency.csr_of_pairs")
    lo, hi = np.ascontiguousarray(lo), np.ascontiguousarray(hi)  # (columns of the pairs)
    e = lo.shape[0]
    indices = np.empty(2 * e, dtype=np.int32)
    dual_edge = np.empty(2 * e, dtype=adjacency_dtype(2 * e))
    indptr = csr_of_pairs(lo, hi, int(n), indices, dual_edge)
    return indptr, indices, dual_edge


def pairs_from_csr(graph: "ElementGraph", pair_dtype=np.int32) -> dict[str, np.ndarray]:
    """``pairs`` and ``dual_edge`` computed again from the CSR layout.

    The graphs of :mod:`superfacets.elements` list their pairs in ``(lo, hi)``
    order, which is the order of the CSR entries ``(v, g)``, ``g > v``; so the
    two arrays follow from ``indptr`` and ``indices`` alone, the same as built.

    Parameters
    ----------
    graph : ElementGraph
    pair_dtype : numpy dtype, default int32
        The dtype of ``pairs`` as built (int64 from ``2**31`` elements on).

    Returns
    -------
    dict
        ``{"pairs": (e, 2) ndarray, "dual_edge": (2 e,) int32 or int64 ndarray}``.
    """

    number_pairs = native.kernel("adjacency.number_pairs")
    n_csr = graph.indices.shape[0]
    pairs = np.empty((n_csr // 2, 2), dtype=pair_dtype)
    dual_edge = np.empty(n_csr, dtype=adjacency_dtype(n_csr))
    number_pairs(graph.indptr, graph.indices, graph.n_elements, dual_edge,
                 np.empty(0, dtype=np.int64), pairs)
    return {"pairs": pairs, "dual_edge": dual_edge}


#: Given for a field of :class:`ElementGraph` that has a ``rebuild`` entry: the field is
#: not built until something reads it (a point graph's pairs, dual-edge map, spans and
#: border lengths, which a default run on points never reads).
LAZY = object()


class _Rebuilt:
    """A field of :class:`ElementGraph` that :meth:`ElementGraph.release` may forget:
    on next use it is computed again, the same, by ``graph.rebuild[name](graph)``
    (a dict of one or more fields, each stored if absent). ``optional``: the field
    defaults to None (a graph without a rebuild entry for it keeps None). Given as
    :data:`LAZY`, it is built on first use."""

    def __init__(self, optional: bool = False) -> None:
        self.optional = optional

    def __set_name__(self, owner, name: str) -> None:
        self.name = name

    def __get__(self, graph, owner=None):
        if graph is None:  # class access: the dataclass field's default, if any
            if self.optional:
                return None
            raise AttributeError(self.name)
        d = graph.__dict__
        try:
            return d[self.name]
        except KeyError:
            make = graph.rebuild.get(self.name)
            if make is None:  # an optional field never given
                return None
            for name, value in make(graph).items():
                d.setdefault(name, value)
            return d[self.name]

    def __set__(self, graph, value) -> None:  # the dataclass's __init__ only (frozen)
        if value is not LAZY:
            graph.__dict__[self.name] = value


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
    """Elements and their adjacency (faces: the face graph; vertices: the mesh edges;
    points: the symmetric k-nearest-neighbour graph).

    Attributes
    ----------
    kind : str
        What the elements are: ``"faces"``, ``"vertices"`` or ``"points"``.
    positions : (n, 3) float64 ndarray
        Position of each element (faces: centroid; vertices, points: itself).
    sizes : (n,) float64 ndarray
        Size of each element, in squared mesh units: the surface area it
        stands for (faces: area; vertices: a third of the incident triangles'
        areas; points: the k-nearest-neighbour estimate), the weight of its
        position in a superfacet's mean and of the metrics.
    normals : (n, 3) float64 ndarray (points: float32)
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
    pairs : (e, 2) int ndarray
        The two elements ``(i, j)``, ``i < j``, of each adjacency, sorted
        (faces: int32 while face ids fit, int64 beyond).
    indptr : (n + 1,) int64 ndarray
        CSR row pointers: neighbours of ``f`` are ``indices[indptr[f]:indptr[f + 1]]``.
    indices : (2 e,) int32 ndarray
        CSR column indices (neighbours), ascending within a row.
    dual_edge : (2 e,) int32 or int64 ndarray
        Index into ``pairs`` of each CSR entry: per-adjacency arrays map onto
        CSR as ``values[graph.dual_edge]``.
    lengths : (e,) float64 ndarray
        Length of the border each adjacent pair shares (faces: the mesh edge;
        vertices: the dual edge of the barycentric cells; points: an estimate,
        see :func:`~superfacets.elements.point_graph`).
    boundary_elements : (b,) int64 ndarray
        Element of each open border piece (faces: edge used by one face).
    boundary_lengths : (b,) float64 ndarray
        Length of each open border piece.
    edges : (e, 2) int ndarray or None
        Faces: the shared mesh edge ``(a, b)``, ``a < b``, of each adjacency
        (int32 while vertex ids fit, int64 beyond).
    boundary_edges : (b, 2) int64 ndarray or None
        Faces: the open-boundary mesh edges, ``a < b``.
    spans : (e,) float64 ndarray or None
        The length that scales the angular term of the paper's weights (eq. 2)
        when it differs from ``lengths`` (vertices, points: the distance
        between the two elements); see :attr:`span`.
    border_shares : (n,) float64 ndarray or None
        Points: each element's share of the border of each of its adjacencies; the
        border length of the adjacency ``(i, j)`` is ``(share_i + share_j) / 2``
        (:func:`~superfacets.elements.point_graph`), so the kernels that sum border
        lengths read these 8 bytes per element instead of ``lengths`` (8 per
        adjacency, then never built). None: read ``lengths``.
    scale2 : (n,) float64 ndarray or None
        Content-sensitive runs (:mod:`superfacets.elements.density`): the squared scale of
        each element, by which the farthest-point centers multiply squared
        distances; None: 1.
    terms_of : callable or None
        ``terms_of(graph, sl) -> (geo, cos, concave)`` for a slice of the
        pairs: the :class:`AdjacencyTerms` of those adjacencies.
    rebuild : mapping of str to callable
        For the fields :meth:`release` may forget (``normals``, ``pairs``,
        ``dual_edge``, ``lengths``, ``spans``, ``border_shares``, and a triangle mesh's
        ``edges``):
        ``rebuild[name](graph)`` computes that field again, the same, as a dict of
        fields. A field without an entry is never released.

    Examples
    --------
    >>> g = face_graph(as_mesh(trimesh.creation.box()))
    >>> g.kind, g.n_elements, g.pairs.shape, g.indptr.shape
    ('faces', 12, (18, 2), (13,))
    """

    kind: str
    positions: np.ndarray
    sizes: np.ndarray
    normals: np.ndarray = _Rebuilt()
    centroid: np.ndarray
    lower: np.ndarray
    diagonal: float
    pairs: np.ndarray = _Rebuilt()
    indptr: np.ndarray
    indices: np.ndarray
    dual_edge: np.ndarray = _Rebuilt()
    lengths: np.ndarray = _Rebuilt()
    boundary_elements: np.ndarray
    boundary_lengths: np.ndarray
    edges: np.ndarray | None = _Rebuilt(optional=True)
    boundary_edges: np.ndarray | None = None
    spans: np.ndarray | None = _Rebuilt(optional=True)
    border_shares: np.ndarray | None = _Rebuilt(optional=True)
    scale2: np.ndarray | None = None
    terms_of: Callable[["ElementGraph", slice], tuple] | None = field(default=None, repr=False)
    rebuild: Mapping[str, Callable[["ElementGraph"], dict]] = field(default_factory=dict,
                                                                    repr=False)

    @property
    def element(self) -> str:
        """The singular of ``kind``: ``"face"``, ``"vertex"`` or ``"point"``."""

        return KINDS[self.kind].singular if self.kind in KINDS else self.kind

    @property
    def n_elements(self) -> int:
        """Number of elements ``n``."""
        return int(self.positions.shape[0])

    @property
    def n_edges(self) -> int:
        """Number of adjacent pairs ``e`` (half the CSR entries: the pairs are not built
        for it)."""
        return int(self.indices.shape[0] // 2)

    def border_arrays(self) -> tuple[np.ndarray, np.ndarray]:
        """``(lengths, shares)`` for the kernels that sum border lengths in pair order:
        ``(empty, border_shares)`` where the graph has shares (the length of pair ``(i,
        j)`` is then ``0.5 * (shares[i] + shares[j])``), else ``(lengths, empty)``."""
        if self.border_shares is not None:
            return np.empty(0), self.border_shares
        return self.lengths, np.empty(0)

    def replaced(self, **changes) -> "ElementGraph":
        """:func:`dataclasses.replace` that leaves the fields not built yet (or released)
        unbuilt in the copy: they are built there on first use, as here. Cached
        properties (:attr:`terms`, :attr:`area`) are not carried over."""
        given = {f.name: self.__dict__.get(f.name, LAZY) for f in fields(self) if f.init}
        given.update(changes)
        return type(self)(**given)

    @property
    def span(self) -> np.ndarray:
        """(e,) float64: the length scaling the angular term of each adjacency (eq. 2):
        ``spans``, or the border ``lengths`` (faces: the shared mesh edge)."""
        return self.lengths if self.spans is None else self.spans

    @cached_property
    def area(self) -> float:
        """Total size ``A`` (faces: surface area)."""
        return float(self.sizes.sum())

    @cached_property
    def terms(self) -> AdjacencyTerms:
        """The :class:`AdjacencyTerms` of every adjacency, computed once (in chunks,
        ranges of chunks on threads)."""

        e = self.n_edges
        geo, cos = np.empty(e), np.empty(e)
        concave = np.empty(e, dtype=bool)
        self.normals, self.pairs, self.edges  # noqa: B018 (rebuilt here if released, not on
        # the threads)

        def chunks(c0: int, c1: int) -> None:
            for s in range(c0 * CHUNK, min(e, c1 * CHUNK), CHUNK):
                sl = slice(s, min(e, s + CHUNK))
                geo[sl], cos[sl], concave[sl] = self.terms_of(self, sl)

        threads.run_ranges(chunks, split(-(-e // CHUNK), min_per_thread=1))
        return AdjacencyTerms(geo, cos, concave)

    def terms_in(self, sl: slice) -> AdjacencyTerms:
        """The :class:`AdjacencyTerms` of the adjacencies ``sl``: slices of :attr:`terms`
        once those are computed, else computed for ``sl`` alone and not kept (the
        weights need each term once: a run without the clean-up never holds all
        of them, 17 B per adjacency). The same values either way."""
        t = self.__dict__.get("terms")
        if t is None and self.terms_of is not None:
            return AdjacencyTerms(*self.terms_of(self, sl))
        t = self.terms
        return AdjacencyTerms(t.geo[sl], t.cos[sl], t.concave[sl])

    def release_terms(self) -> None:
        """Forget the cached :attr:`terms` (about 17 bytes per adjacency); they are
        computed again, the same, on next use. The pipeline calls it once the
        weights are made, so the terms do not stay in memory during the passes."""
        self.__dict__.pop("terms", None)

    def release(self, keep: tuple = ()) -> None:
        """Forget the fields that have a :attr:`rebuild` entry (faces: the
        normals, pairs, dual-edge map and border lengths, about 60 bytes per
        face, with the mesh's cached normals, and a triangle mesh's shared edges, 12 more;
        points: the pairs, dual-edge map,
        border lengths and spans, about 160 bytes per point); each is computed again, the
        same, on next use. The pipeline calls it before the passes, which
        read only the CSR layout, the positions and the sizes, so that the
        passes' peak memory does not hold them; and, keeping the normals and
        lengths, before the coarsening, which reads those and the CSR layout.

        Parameters
        ----------
        keep : tuple of str
            Fields to keep all the same.
        """
        for name, make in self.rebuild.items():
            if name in keep:
                continue
            self.__dict__.pop(name, None)
            forget = getattr(make, "release", None)
            if forget is not None:
                forget()

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


def cached_on(owner, key: str, build: Callable[[], object]):
    """``build()``, computed once and kept with ``owner`` (a mesh or a cloud) under ``key``.

    The element graphs belong to this package, not to the inputs they are built
    from: a :class:`~superfacets.inputs.mesh.Mesh` or :class:`~superfacets.inputs.cloud.PointCloud`
    only lends its attribute dictionary, so it never imports a builder. Its
    arrays are read-only, so a kept graph never goes stale; a pickled input
    leaves its graphs behind (they hold functions) and builds them again.
    """
    store = owner.__dict__
    value = store.get(key)
    if value is None:
        value = store[key] = build()
    return value
