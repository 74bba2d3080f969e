"""The k nearest neighbours of each point, queried in blocks (the point graph's first step).

scipy's KD-tree answers a query of ``m`` points with two ``(m, k + 1)`` arrays of 8-byte
numbers. For the whole cloud at once those are 192 bytes per point at ``k = 10``, more than
the rest of the point graph needs at its peak. :func:`nearest` queries blocks of
:data:`BLOCK` points and keeps only what the graph reads: the neighbours as 4-byte indices,
the distance to the ``k``-th and, with a radius, which neighbours lie within it (44 + 8,
and 10 more with a radius, bytes per point at ``k = 10``). Each query is answered alone,
so the result is the same for any block size, bit for bit.

Ties at the ``k``-th distance (quantized scans) go to the lowest index, and each point is
its own first neighbour (:func:`superfacets.elements.points.point_graph`).
"""

from __future__ import annotations

import numpy as np

__all__ = ["BLOCK", "nearest"]

#: Queries per block: bounds the KD-tree's answer to about 12 MiB at ``k = 10``.
BLOCK = 1 << 16


def nearest(tree, pts: np.ndarray, queries: np.ndarray, k: int, own: np.ndarray | None = None,
            limit: float | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
    """The ``k + 1`` nearest points of each query, itself first, in blocks.

    Parameters
    ----------
    tree : scipy.spatial.cKDTree
        Over ``pts``.
    pts : (n, 3) float64 ndarray
        The points of the tree.
    queries : (m, 3) float64 ndarray
        Positions to query, each one of the points.
    k : int
        Neighbours besides the point itself, ``1 <= k < n``.
    own : (m,) int ndarray, optional
        The index of each query among ``pts`` (default: ``0 .. m - 1``).
    limit : float, optional
        Also say which neighbours lie within this distance.

    Returns
    -------
    neighbors : (m, k + 1) int32 ndarray (int64 from 2**31 points on)
        Column 0: the query itself; then by distance, ties at the ``k``-th distance to
        the lowest index.
    kth : (m,) float64 ndarray
        The distance to the ``k``-th neighbour (the last column).
    within : (m, k) bool ndarray or None
        With ``limit``: ``distance <= limit`` for columns ``1 .. k``.

    Examples
    --------
    >>> from scipy.spatial import cKDTree
    >>> pts = np.c_[np.arange(5.0), np.zeros(5), np.zeros(5)]
    >>> nbr, kth, within = nearest(cKDTree(pts), pts, pts, 2, limit=1.5)
    >>> nbr[2].tolist(), kth.tolist(), within[0].tolist()
    ([2, 1, 3], [2.0, 1.0, 1.0, 1.0, 2.0], [True, False])
    """
    m = queries.shape[0]
    dtype = np.int32 if pts.shape[0] < 2**31 else np.int64
    neighbors = np.empty((m, k + 1), dtype=dtype)
    kth = np.empty(m)
    within = None if limit is None else np.empty((m, k), dtype=bool)
    for s in range(0, m, BLOCK):
        e = min(m, s + BLOCK)
        rows = np.arange(s, e) if own is None else own[s:e]
        dist, nbr = _query(tree, pts, queries[s:e], k, rows)
        neighbors[s:e] = nbr
        kth[s:e] = dist[:, k]
        if within is not None:
            within[s:e] = dist[:, 1:] <= limit
    return neighbors, kth, within


def _query(tree, pts: np.ndarray, queries: np.ndarray, k: int, own: np.ndarray
           ) -> tuple[np.ndarray, np.ndarray]:
    """The ``k + 1`` nearest points of each query, itself first (``own``: the queries'
    indices among the points), ties at the k-th distance to the lowest index
    (:func:`_break_ties`)."""
    m = queries.shape[0]
    extra = 1 if k + 1 < pts.shape[0] else 0  # one column more to see ties
    dist, nbr = tree.query(queries, k=k + 1 + extra, workers=-1)
    dist, nbr = dist.reshape(m, -1), nbr.reshape(m, -1)
    if extra:
        _break_ties(tree, pts, dist, nbr, k, queries)
    _itself_first(nbr, own)
    if extra:
        dist, nbr = dist[:, :k + 1], nbr[:, :k + 1]
    return dist, nbr


def _break_ties(tree, pts: np.ndarray, dist: np.ndarray, nbr: np.ndarray, k: int,
                queries: np.ndarray) -> None:
    """Where the k-th and the next neighbour are equally far (quantized scans), keep the
    tied neighbours of lowest index, in place: the KD-tree's own choice depends on the
    whole cloud, the lowest index (the position's place in
    :func:`~superfacets.elements.points.distinct_points`' order) does not, so a tile of a
    cloud (:mod:`superfacets.scale.tiling`) gets the whole cloud's graph inside its halo.
    ``queries``: the positions queried, row by row."""
    tied = np.flatnonzero(dist[:, k] == dist[:, k + 1])
    if not tied.size:
        return
    reach = tree.query_ball_point(queries[tied], dist[tied, k] * (1 + 1e-9), workers=-1)
    for row, found in zip(tied.tolist(), reach):
        cand = np.sort(np.asarray(found, dtype=np.int64))
        d = np.sqrt(((pts[cand] - queries[row]) ** 2).sum(axis=1))
        pick = cand[np.argsort(d, kind="stable")[:k + 1]]  # ties: the lower index first
        nbr[row, :k + 1] = pick
        dist[row, :k + 1] = np.sqrt(((pts[pick] - queries[row]) ** 2).sum(axis=1))


def _itself_first(nbr: np.ndarray, own: np.ndarray) -> None:
    """Put each query's own index in column 0, in place, the others shifted right.

    A point is its own nearest at distance 0, but distinct points closer than about
    1e-154 are at distance 0 too (the squared distance underflows), and the tree may
    list such a twin first; as a neighbour of itself a point would then be an edge of
    its own. (Their distances are all 0: only the indices move.)"""
    for r in np.flatnonzero(nbr[:, 0] != own).tolist():
        at = np.flatnonzero(nbr[r] == own[r])
        end = int(at[0]) if at.size else nbr.shape[1] - 1  # not listed: drop the last
        nbr[r, 1:end + 1] = nbr[r, :end].copy()
        nbr[r, 0] = own[r]
