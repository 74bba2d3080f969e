"""What the merges to the count read, as sums that add up: per superpoint and per pair
of adjacent superpoints, and the superpoint graph of any grouping of them.

The merges (:mod:`superfacets.method.merges`) join superpoints, never split them, so
everything their costs read can be summed once over the first superpoints and added up
for any union of them: per superpoint the points' count, mean and scatter (the
least-squares plane of the flat merges and of the plane's rise) and the area and
area-weighted mean (Ward's cost); per pair of adjacent superpoints the border length,
the border-weighted angle and concave share of the normals (the crease factor) and the
plain sums where a border has no length. One run sums them over its whole graph
(:func:`border_sums`, :func:`point_sums`); a tiled run over each tile's core, added in
the driver (:mod:`superfacets.scale.tiles.merges`); both merge the same sums the same way.

On a point graph whose adjacencies were never listed (a default run) the pairs' sums are
made in one pass over its layout (``label_pair_sums``): no array per crossing adjacency
(millions of them on a large cloud).
"""

from __future__ import annotations

import numpy as np

from .._kernels import native
from ..elements.vertices import symmetric_terms
from .adjacency import SuperfacetGraph, crossing_adjacencies

__all__ = ["border_sums", "point_sums", "pair_sums", "grouped_graph", "grouped_planes",
           "area_moments",
           "PAIR_FIELDS"]

#: The per-pair sums, in the columns of ``label_pair_sums``: border length, border times
#: angle, border times concave share, crossings, angle, concave share.
PAIR_FIELDS = ("border", "angle", "concave", "crossings", "angle_sum", "concave_sum")

#: The largest label + 1 whose pairs :func:`pair_sums` keys as one int64 (its square fits).
_ONE_KEY = 3_037_000_499


def border_sums(graph, labels: np.ndarray, k: int) -> dict:
    """The element adjacencies that cross ``labels``, summed per pair of labels.

    Parameters
    ----------
    graph : ElementGraph
    labels : (n,) int64 ndarray
        A label per element, in ``0..k-1``.
    k : int
        The number of labels.

    Returns
    -------
    dict
        ``edges`` (E, 2) int64, the two labels of each pair, lower first, sorted, and per
        pair the :data:`PAIR_FIELDS` ((E,) float64).

    Raises
    ------
    ValueError
        If the labels do not fit the graph (the kernel checks them).

    Examples
    --------
    >>> xy = np.stack(np.meshgrid(np.arange(10.0), np.arange(10.0)), -1).reshape(-1, 2)
    >>> g = point_graph(PointCloud(np.c_[xy, np.zeros(100)])).graph
    >>> s = border_sums(g, (g.positions[:, 0] >= 5).astype(np.int64), 2)
    >>> s["edges"].tolist(), s["concave_sum"].tolist()
    ([[0, 1]], [0.0])
    """

    lab = np.ascontiguousarray(labels, dtype=np.int64)
    if (graph.border_shares is None or graph.terms_of is not symmetric_terms
            or "pairs" in graph.__dict__ or "terms" in graph.__dict__):
        pc, length, cos, concave = crossing_adjacencies(graph, lab)
        return pair_sums(lab[pc[:, 0]], lab[pc[:, 1]], length,
                         np.arccos(np.clip(cos, -1.0, 1.0)), concave.astype(np.float64))
    keys, sums = native.kernel("borders.label_pair_sums")(
        graph.indptr, graph.indices, lab, int(k), np.ascontiguousarray(graph.positions),
        graph.normals, np.ascontiguousarray(graph.border_shares, dtype=np.float64))
    kk = max(int(k), 1)
    return dict(edges=np.stack([keys // kk, keys % kk], 1).astype(np.int64),
                **{f: np.ascontiguousarray(sums[:, c]) for c, f in enumerate(PAIR_FIELDS)})


def pair_sums(a: np.ndarray, b: np.ndarray, length: np.ndarray, angle: np.ndarray,
              concave: np.ndarray) -> dict:
    """Adjacencies between superpoints ``a`` and ``b`` (labels or names, one per
    adjacency, with its border length, angle and concave share) summed per pair, as
    :func:`border_sums` returns them.

    Examples
    --------
    >>> s = pair_sums(np.array([5, 2, 5]), np.array([2, 5, 9]), np.ones(3),
    ...               np.array([0.1, 0.3, 0.5]), np.zeros(3))
    >>> s["edges"].tolist(), s["crossings"].tolist(), s["angle_sum"].round(2).tolist()
    ([[2, 5], [5, 9]], [2.0, 1.0], [0.4, 0.5])
    """
    lo, hi = np.minimum(a, b).astype(np.int64), np.maximum(a, b).astype(np.int64)
    m = int(hi.max()) + 1 if hi.size else 1
    if lo.size and (int(lo.min()) < 0 or m > _ONE_KEY):  # (names too large for one key)
        key, inv = np.unique(np.stack([lo, hi], 1), axis=0, return_inverse=True)
    else:  # one int64 key a pair, in the same order as the pairs (a sort, not a lexsort)
        one, inv = np.unique(lo * np.int64(m) + hi, return_inverse=True)
        key = np.stack([one // m, one % m], 1)
    inv = inv.reshape(-1)
    e = key.shape[0]

    def add(w):
        return np.bincount(inv, weights=w, minlength=e)

    return dict(edges=key.reshape(e, 2).astype(np.int64), border=add(length),
                angle=add(length * angle), concave=add(length * concave),
                crossings=np.bincount(inv, minlength=e).astype(np.float64),
                angle_sum=add(angle), concave_sum=add(concave))


def point_sums(labels: np.ndarray, k: int, positions: np.ndarray, normals: np.ndarray,
               sizes: np.ndarray, features: np.ndarray | None = None) -> dict:
    """Per superpoint: its points' ``count``, ``mean`` (k, 3) and ``scatter`` (k, 3, 3)
    about that mean (each point weighs one), its ``area`` and area-weighted mean
    ``area_mean`` (k, 3); with ``features`` (n, d), their ``feature_sum`` and
    ``feature_squares`` (k, d).

    Parameters
    ----------
    labels : (n,) int64 ndarray
        In ``0..k-1``.
    k : int
    positions : (n, 3) float64 ndarray
    normals : (n, 3) float ndarray
    sizes : (n,) float64 ndarray
        The elements' areas.
    features : (n, d) float64 ndarray, optional

    Returns
    -------
    dict

    Examples
    --------
    >>> pos = np.array([[0.0, 0, 0], [2, 0, 0], [5, 5, 5]])
    >>> s = point_sums(np.array([0, 0, 1]), 2, pos, np.zeros((3, 3)), np.ones(3))
    >>> s["count"].tolist(), s["mean"][0].tolist(), float(s["scatter"][0, 0, 0])
    ([2.0, 1.0], [1.0, 0.0, 0.0], 2.0)
    """
    sums = native.kernel("geometry.label_sums")
    lab = np.ascontiguousarray(labels, dtype=np.int64)
    pos = np.ascontiguousarray(positions, dtype=np.float64)
    count, wpos, unused = np.zeros(k), np.zeros((k, 3)), np.zeros((k, 3))
    ones = np.ones(lab.size)
    sums(lab, ones, pos, normals, count, wpos, unused)
    mean = wpos / np.maximum(count, 1.0)[:, None]
    scatter = np.zeros((k, 9))
    native.kernel("geometry.label_scatter")(lab, ones, pos, mean, scatter)
    area, apos = np.zeros(k), np.zeros((k, 3))
    sums(lab, np.ascontiguousarray(sizes, dtype=np.float64), pos, normals, area, apos, unused)
    out = dict(count=count, mean=mean, scatter=scatter.reshape(k, 3, 3), area=area,
               area_mean=apos / np.where(area > 0, area, 1.0)[:, None])
    if features is not None:
        for name, f in (("feature_sum", lambda x: x), ("feature_squares", np.square)):
            out[name] = np.stack([np.bincount(lab, weights=f(features[:, c]), minlength=k)
                                  for c in range(features.shape[1])], 1)
    return out


def area_moments(labels: np.ndarray, k: int, positions: np.ndarray, normals: np.ndarray,
                 sizes: np.ndarray, area_mean: np.ndarray, colours=None) -> dict:
    """Per superpoint, what its superpoint graph's node holds beyond :func:`point_sums`
    (:func:`superfacets.graph.adjacency.superfacet_graph`, each element weighed by its
    area): the area-weighted sum of the normals ``area_normal`` (k, 3), the scatter
    ``area_scatter`` (k, 3, 3) about the area-weighted mean ``area_mean``, and with
    ``colours`` (n, d) their area-weighted sum ``area_colour`` (k, d).

    Parameters
    ----------
    labels : (n,) int64 ndarray
        In ``0..k-1``.
    k : int
    positions : (n, 3) float64 ndarray
    normals : (n, 3) float ndarray
    sizes : (n,) float64 ndarray
    area_mean : (k, 3) float64 ndarray
        :func:`point_sums`' ``area_mean``.
    colours : (n, d) float64 ndarray, optional

    Returns
    -------
    dict

    Raises
    ------
    Never for arrays of these shapes.

    Examples
    --------
    >>> pos = np.array([[0.0, 0, 0], [2, 0, 0]])
    >>> up = np.array([[0.0, 0, 1], [0.0, 0, 1]])
    >>> m = area_moments(np.zeros(2, np.int64), 1, pos, up, np.array([1.0, 3.0]),
    ...                  np.array([[1.5, 0, 0]]))
    >>> m["area_normal"].tolist(), float(m["area_scatter"][0, 0, 0])
    ([[0.0, 0.0, 4.0]], 3.0)
    """
    sums = native.kernel("geometry.label_sums")
    lab = np.ascontiguousarray(labels, dtype=np.int64)
    pos = np.ascontiguousarray(positions, dtype=np.float64)
    size = np.ascontiguousarray(sizes, dtype=np.float64)
    area, apos, normal = np.zeros(k), np.zeros((k, 3)), np.zeros((k, 3))
    sums(lab, size, pos, normals, area, apos, normal)
    scatter = np.zeros((k, 9))
    native.kernel("geometry.label_scatter")(lab, size, pos, np.ascontiguousarray(
        area_mean, dtype=np.float64), scatter)
    out = dict(area_normal=normal, area_scatter=scatter.reshape(k, 3, 3))
    if colours is not None:
        c = np.asarray(colours, dtype=np.float64).reshape(lab.size, -1)
        out["area_colour"] = np.stack([np.bincount(lab, weights=size * c[:, j], minlength=k)
                                       for j in range(c.shape[1])], 1)
    return out


def grouped_planes(top: np.ndarray, count: np.ndarray, mean: np.ndarray,
                   scatter: np.ndarray) -> tuple:
    """The points' count, mean and scatter of the superpoints grouped by ``top`` (Chan's
    rule: each part's scatter about the union's mean), as a planarity level reads them
    (:func:`superfacets.graph.hierarchy.planarity_graph`); with areas for ``count`` and
    area-weighted means and scatters, the area-weighted ones.

    Examples
    --------
    >>> c, m, s = grouped_planes(np.array([0, 0]), np.ones(2), np.array([[0.0, 0, 0],
    ...                                                                  [2, 0, 0]]),
    ...                          np.zeros((2, 3, 3)))
    >>> c.tolist(), m.tolist(), float(s[0, 0, 0])
    ([2.0], [[1.0, 0.0, 0.0]], 2.0)
    """
    g = int(top.max()) + 1 if top.size else 0
    total = np.bincount(top, weights=count, minlength=g)
    gmean = np.stack([np.bincount(top, weights=count * mean[:, c], minlength=g)
                      for c in range(3)], 1) / np.where(total > 0, total, 1.0)[:, None]
    d = mean - gmean[top]
    part = (scatter + count[:, None, None] * d[:, :, None] * d[:, None, :]).reshape(-1, 9)
    gscatter = np.stack([np.bincount(top, weights=part[:, j], minlength=g) for j in range(9)],
                        1).reshape(g, 3, 3)  # (in the nodes' order, as np.add.at adds)
    return total, gmean, gscatter


def grouped_graph(of_node: np.ndarray, edges: np.ndarray, parts: dict, area: np.ndarray,
                  centroid: np.ndarray, scatter=None) -> SuperfacetGraph:
    """The superpoint graph of nodes grouped by ``of_node``: the edges between groups (the
    same pair any number of times), their sums added, the border-weighted means (plain
    where a border has no length).

    Parameters
    ----------
    of_node : (K,) int64 ndarray
        The group of each node, dense ``0..G-1``.
    edges : (E, 2) int64 ndarray
        Node pairs.
    parts : dict
        Per pair the :data:`PAIR_FIELDS`.
    area, centroid : (G,), (G, 3) float64 ndarray
        The groups' (their points' count and mean for a planarity level).
    scatter : (G, 3, 3) float64 ndarray, optional

    Returns
    -------
    SuperfacetGraph

    Examples
    --------
    >>> parts = dict(zip(PAIR_FIELDS, np.ones((6, 3))))
    >>> sg = grouped_graph(np.array([0, 0, 1, 1]), np.array([[0, 1], [1, 2], [2, 3]]),
    ...                    parts, np.ones(2), np.zeros((2, 3)))
    >>> sg.edge_index.tolist(), sg.border_length.tolist()
    ([[0], [1]], [1.0])
    """
    k = area.shape[0]
    a, b = of_node[edges[:, 0]], of_node[edges[:, 1]]
    cross = a != b
    lo, hi = np.minimum(a, b)[cross], np.maximum(a, b)[cross]
    key, inv = np.unique(lo * max(k, 1) + hi, return_inverse=True)
    e = key.size

    def add(f):
        return np.bincount(inv, weights=parts[f][cross], minlength=e)

    border, n_cross = add("border"), add("crossings")
    zero = border <= 0
    mean_angle = add("angle") / np.where(zero, 1.0, border)
    concave = add("concave") / np.where(zero, 1.0, border)
    if zero.any():
        mean_angle[zero] = (add("angle_sum") / np.maximum(n_cross, 1.0))[zero]
        concave[zero] = (add("concave_sum") / np.maximum(n_cross, 1.0))[zero]
    return SuperfacetGraph(edge_index=np.stack([key // max(k, 1), key % max(k, 1)]).astype(
        np.int64), border_length=border, mean_angle=mean_angle, concave=concave, area=area,
        centroid=centroid, normal=np.zeros((k, 3)), feature=None, scatter=scatter)
