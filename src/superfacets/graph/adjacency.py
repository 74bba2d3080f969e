"""The superfacet graph: superfacets (or superpoints) as nodes, shared borders as edges.

Two superfacets are adjacent when two of their elements are (faces sharing an
edge, vertices joined by a mesh edge, points among each other's nearest
neighbours). What a graph network, a region-merging step or a viewer needs of
each is kept as plain numpy arrays: per node the area, the area-weighted
centroid, normal and feature; per edge the border length, the mean angle
between the element normals across the border and the concave share of the
border. :meth:`SuperfacetGraph.to_scipy` and :meth:`SuperfacetGraph.to_networkx`
hand it to those libraries; :meth:`SuperfacetGraph.save` writes it to ``.npz``.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .._kernels import native
from .._runtime.arrays import real_rows
from ..elements.builders import as_element_graph
from ..elements.labels import check_labels
from ..elements.vertices import symmetric_terms
from ..errors import ParameterError
from ..io.files import atomic_write

__all__ = ["SuperfacetGraph", "superfacet_graph", "crossing_adjacencies"]


@dataclass(frozen=True)
class SuperfacetGraph:
    """Adjacency of the superfacets of one segmentation.

    Attributes
    ----------
    edge_index : (2, E) int64 ndarray
        The two superfacets of each adjacency, ``edge_index[0] < edge_index[1]``,
        sorted; each pair once.
    border_length : (E,) float64 ndarray
        Length of the shared border, in mesh units (the summed border
        lengths of the element adjacencies that cross it; points: the
        estimate of :mod:`superfacets.elements.points`).
    mean_angle : (E,) float64 ndarray
        Border-length-weighted mean angle between the element normals across
        the border, in radians, ``[0, pi]`` (faces: the unsigned dihedral
        angle of paper eq. 2).
    concave : (E,) float64 ndarray
        Fraction of the border length on concave adjacencies (paper eq. 2's
        test), ``[0, 1]``.
    area : (K,) float64 ndarray
        Area of each superfacet (points: the area the points stand for).
    centroid : (K, 3) float64 ndarray
        Area-weighted mean position of its elements.
    normal : (K, 3) float64 ndarray
        Area-weighted mean normal, made unit (zero where the normals cancel).
    feature : (K, d) float64 ndarray or None
        Area-weighted mean of the per-element features given, if any.
    scatter : (K, 3, 3) float64 ndarray or None
        Area-weighted scatter of the element positions about the centroid,
        ``sum_i a_i (p_i - c)(p_i - c)^T`` (mesh units^4); its smallest
        eigenvalue is the area-weighted squared distance to the best plane.

    Examples
    --------
    >>> g = segment(trimesh.creation.icosphere(subdivisions=3), 12).graph()
    >>> g.n_segments, g.edge_index.shape[0], g.area.shape
    (12, 2, (12,))
    """

    edge_index: np.ndarray
    border_length: np.ndarray
    mean_angle: np.ndarray
    concave: np.ndarray
    area: np.ndarray
    centroid: np.ndarray
    normal: np.ndarray
    feature: np.ndarray | None = None
    scatter: np.ndarray | None = field(default=None, repr=False)

    @property
    def n_segments(self) -> int:
        """Number of nodes ``K``."""
        return int(self.area.shape[0])

    @property
    def n_edges(self) -> int:
        """Number of adjacent pairs ``E``."""
        return int(self.edge_index.shape[1])

    def to_scipy(self, weight: str = "border_length"):
        """The symmetric ``(K, K)`` scipy CSR matrix of one edge attribute.

        Parameters
        ----------
        weight : {'border_length', 'mean_angle', 'concave'}, default 'border_length'

        Returns
        -------
        scipy.sparse.csr_matrix
            ``M[a, b] = M[b, a]`` = the attribute of the pair ``(a, b)``.

        Raises
        ------
        ParameterError
            If ``weight`` is not an edge attribute.
        """
        from scipy.sparse import csr_matrix

        if weight not in ("border_length", "mean_angle", "concave"):
            raise ParameterError(f"weight must be border_length, mean_angle or concave, "
                                 f"got {weight!r}")
        w = getattr(self, weight)
        a, b = self.edge_index
        k = self.n_segments
        return csr_matrix((np.r_[w, w], (np.r_[a, b], np.r_[b, a])), shape=(k, k))

    def to_networkx(self):
        """A ``networkx.Graph``: node ``s`` with ``area``, ``centroid``, ``normal``
        (and ``feature``), edges with ``border_length``, ``mean_angle`` and ``concave``.

        Raises
        ------
        ImportError
            Naming the package to install, if networkx is missing.
        """
        try:
            import networkx as nx
        except ImportError:  # pragma: no cover - depends on the environment
            raise ImportError("to_networkx needs networkx: pip install networkx") from None
        g = nx.Graph()
        for s in range(self.n_segments):
            attrs = dict(area=float(self.area[s]), centroid=self.centroid[s].tolist(),
                         normal=self.normal[s].tolist())
            if self.feature is not None:
                attrs["feature"] = self.feature[s].tolist()
            g.add_node(s, **attrs)
        for t in range(self.n_edges):
            g.add_edge(int(self.edge_index[0, t]), int(self.edge_index[1, t]),
                       border_length=float(self.border_length[t]),
                       mean_angle=float(self.mean_angle[t]), concave=float(self.concave[t]))
        return g

    def arrays(self) -> dict[str, np.ndarray]:
        """The attributes as a dict of arrays (``feature`` left out when None)."""
        out = {name: getattr(self, name) for name in
               ("edge_index", "border_length", "mean_angle", "concave", "area", "centroid",
                "normal")}
        if self.feature is not None:
            out["feature"] = self.feature
        return out

    def save(self, path, **extra: np.ndarray) -> None:
        """Write the arrays (and ``extra`` ones) to one ``.npz`` file, atomically."""

        atomic_write(path, lambda fh: np.savez_compressed(fh, **self.arrays(), **extra))


def superfacet_graph(graph, labels, features=None) -> SuperfacetGraph:
    """The superfacet graph of per-element labels.

    Parameters
    ----------
    graph : ElementGraph, Mesh, trimesh.Trimesh or (vertices, faces)
        The element graph the labels are of (of a mesh: its face graph).
    labels : (n,) int ndarray
        Superfacet of each element, ``0..K-1``, each label used.
    features : (n, d) float ndarray, optional
        A feature per element (e.g. RGB colour); its area-weighted mean per
        superfacet becomes ``feature``.

    Returns
    -------
    SuperfacetGraph

    Raises
    ------
    ParameterError
        If the labels or features do not fit the graph, or a label is unused.

    Examples
    --------
    >>> box = as_mesh(trimesh.creation.box())
    >>> sg = superfacet_graph(face_graph(box), segment(box, 6).labels)
    >>> sg.n_segments, sg.n_edges          # the six sides, each meets four
    (6, 12)
    >>> sg.border_length.tolist() == [1.0] * 12, sg.mean_angle.round(4).tolist()[0]
    (True, 1.5708)
    """
    g = as_element_graph(graph)
    lab = np.ascontiguousarray(check_labels(labels, g.n_elements, per=g.element),
                               dtype=np.int64)
    k = int(lab.max()) + 1 if lab.size else 0
    area_w = np.ascontiguousarray(g.sizes, dtype=np.float64)
    if (np.bincount(lab, minlength=k) == 0).any():
        raise ParameterError("labels must use every value 0..K-1 (relabel them densely)")
    pos = np.ascontiguousarray(g.positions, dtype=np.float64)
    # per superfacet, in one pass: the sums np.bincount(lab, weights=...) would make, the
    # same values (element by element in order, each product rounded first)
    area, wpos, normal = np.zeros(k), np.zeros((k, 3)), np.zeros((k, 3))
    native.kernel("geometry.label_sums")(lab, area_w, pos, real_rows(g.normals), area, wpos, normal)
    safe = np.where(area > 0, area, 1.0)
    centroid = wpos / safe[:, None]
    norm = np.linalg.norm(normal, axis=1)
    normal = np.divide(normal, norm[:, None], out=np.zeros_like(normal),
                       where=norm[:, None] > 1e-12 * max(1.0, float(norm.max(initial=0.0))))
    feature = None
    if features is not None:
        f = np.asarray(features, dtype=np.float64)
        f = f.reshape(-1, 1) if f.ndim == 1 else f
        if f.ndim != 2 or f.shape[0] != g.n_elements or not np.isfinite(f).all():
            raise ParameterError(f"features must be a finite ({g.n_elements}, d) array, one "
                                 f"row per {g.element}, got shape {np.shape(features)}")
        feature = np.stack([np.bincount(lab, weights=area_w * f[:, c], minlength=k)
                            for c in range(f.shape[1])], axis=1) / safe[:, None]
    pc, length, cos, concave_el = crossing_adjacencies(g, lab)
    # np.unique(lo * k + hi, return_inverse=True) of each crossing's two labels, by a
    # counting sort on the lower (borders.label_pairs)
    inv = np.empty(pc.shape[0], dtype=np.int64)
    key = native.kernel("borders.label_pairs")(lab, np.ascontiguousarray(pc), k, inv)
    angle = np.arccos(np.clip(cos, -1.0, 1.0))
    e = key.shape[0]
    border = np.bincount(inv, weights=length, minlength=e)
    denom = np.where(border > 0, border, 1.0)
    n_cross = np.bincount(inv, minlength=e).astype(np.float64)
    # border-length weighted; where every crossing has zero length, the plain mean
    zero = border <= 0
    mean_angle = np.bincount(inv, weights=length * angle, minlength=e) / denom
    concave = np.bincount(inv, weights=length * concave_el, minlength=e) / denom
    if zero.any():
        mean_angle[zero] = (np.bincount(inv, weights=angle, minlength=e) / n_cross)[zero]
        concave[zero] = (np.bincount(inv, weights=concave_el.astype(float),
                                     minlength=e) / n_cross)[zero]
    edge_index = np.stack([key // k, key % k]).astype(np.int64) if k else np.zeros((2, 0),
                                                                                   np.int64)
    scatter = np.zeros((k, 9))
    native.kernel("geometry.label_scatter")(lab, area_w, pos, centroid, scatter)
    scatter = scatter.reshape(k, 3, 3)
    return SuperfacetGraph(edge_index=edge_index, border_length=border, mean_angle=mean_angle,
                           concave=concave, area=area, centroid=centroid, normal=normal,
                           feature=feature, scatter=scatter)


def crossing_adjacencies(g, lab: np.ndarray):
    """The element adjacencies whose two elements have different labels, in pair order.

    A point graph whose pairs and terms were never built (a default run) reads them
    from its CSR layout, border shares, positions and normals, for the crossing
    adjacencies alone (the same values: about 60 bytes per point graph adjacency not
    held).

    Parameters
    ----------
    g : ElementGraph
    lab : (n,) int64 ndarray
        A label per element.

    Returns
    -------
    pairs : (m, 2) int ndarray
        The two elements of each, lower first.
    length : (m,) float64 ndarray
        Border length (points: the mean of the two border shares).
    cos : (m,) float64 ndarray
        Cosine of the angle between the two normals.
    concave : (m,) bool ndarray
        Concave adjacencies (paper eq. 3).

    Raises
    ------
    IndexError
        If ``lab`` is shorter than the graph (the caller checks the labels).

    Examples
    --------
    >>> box = as_mesh(trimesh.creation.box())
    >>> lab = segment(box, 6).labels                         # the six sides
    >>> pairs, length, cos, concave = crossing_adjacencies(face_graph(box), lab)
    >>> pairs.shape, float(length[0]), bool(concave.any())   # the 12 edges of the box
    ((12, 2), 1.0, False)
    """

    if (g.border_shares is None or g.terms_of is not symmetric_terms
            or "pairs" in g.__dict__ or "terms" in g.__dict__):
        a, b = lab[g.pairs[:, 0]], lab[g.pairs[:, 1]]
        cross = np.flatnonzero(a != b)
        t = g.terms
        return (g.pairs[cross], np.asarray(g.lengths, dtype=np.float64)[cross],
                t.cos[cross], t.concave[cross])
    crossing_pairs = native.kernel("borders.crossing_pairs")
    point_terms = native.kernel("geometry.point_terms")

    pc = crossing_pairs(g.indptr, g.indices, lab)
    m = pc.shape[0]
    geo, cos, concave = np.empty(m), np.empty(m), np.empty(m, dtype=bool)
    point_terms(np.ascontiguousarray(g.positions),
                real_rows(g.normals), pc, 0, m,
                geo, cos, concave)
    shares = g.border_shares
    return pc, 0.5 * (shares[pc[:, 0]] + shares[pc[:, 1]]), cos, concave
