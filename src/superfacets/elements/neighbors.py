"""The k nearest neighbours of each point, in blocks (the point graph's first step).

:func:`point_tree` builds a tree over a cloud's distinct points in their Z-order (a binary
radix tree of the Z-order keys, node boxes of its points: about 15 bytes per point, no
copy of the points; the compiled kernels' ``nearest``), and :func:`nearest` queries it
in blocks of :data:`BLOCK` points, keeping only what the graph reads: the neighbours as
4-byte indices, the distance to the ``k``-th and, with a radius, which neighbours lie
within it (44 + 8, and 10 more with a radius, bytes per point at ``k = 10``).

Each point's neighbours are its ``k`` nearest other points in the order of (distance,
index), itself first: ties at any distance (quantized scans) go to the lowest index, the
index being the position's place in
:func:`~superfacets.elements.points.distinct_points`' order, so the answer is a function
of the positions alone: a tile of a cloud (:mod:`superfacets.scale.tiling`) gets the
whole cloud's neighbours inside its halo, and no block size or thread count changes a
bit of it. Distances are computed as scipy's KD-tree computes them (the same neighbours
and distances where no two are tied), 1.5 times as fast on two threads, and the tree is
built in a tenth of the time (2M points: 0.06 against 0.49 s).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from .._kernels import native

__all__ = ["BLOCK", "LEAF", "PointTree", "point_tree", "nearest"]

#: Queries per block: bounds the distances of a block to about 6 MiB at ``k = 10``.
BLOCK = 1 << 16
#: Points per leaf of the tree (2M points: 16 and 32 query alike, 8 is 1.5 times slower).
LEAF = 16


class PointTree(NamedTuple):
    """The tree of :func:`point_tree`: node ``v`` holds the rows ``start[v]:end[v]`` of
    ``points``, its children are ``left[v]`` and ``left[v] + 1`` (-1: a leaf), its box
    ``boxes[v]`` (lower corner, upper corner)."""

    points: np.ndarray
    start: np.ndarray
    end: np.ndarray
    left: np.ndarray
    boxes: np.ndarray


def point_tree(points: np.ndarray, leaf: int = LEAF) -> PointTree:
    """The search tree of distinct points in Z-order (see the module notes).

    Parameters
    ----------
    points : (n, 3) float64 ndarray
        Finite, in the order of :func:`~superfacets.elements.points.distinct_points`
        (any order gives the same answers, more slowly).
    leaf : int, default :data:`LEAF`
        Most points in a leaf.

    Returns
    -------
    PointTree
    """
    pts = np.ascontiguousarray(points, dtype=np.float64)
    n = pts.shape[0]
    keys = np.empty((n, 3), dtype=np.uint64)  # the Z-order keys of the points' order
    native.kernel("geometry.float_morton_keys")(pts.view(np.uint64), keys)
    tree_nodes = native.kernel("nearest.tree_nodes")
    cap = n // max(leaf // 4, 1) + 64  # about n / 5 nodes are made at 16 points per leaf
    while True:
        start, end, left = (np.empty(cap, dtype=np.int64) for _ in range(3))
        boxes = np.empty((cap, 6))
        made = tree_nodes(pts, keys, int(leaf), start, end, left, boxes)
        if made >= 0:
            break
        cap = 2 * n + 1  # never more nodes than that
    del keys
    if made < cap:
        start, end, left, boxes = start[:made].copy(), end[:made].copy(), \
            left[:made].copy(), boxes[:made].copy()
    return PointTree(pts, start, end, left, boxes)


def nearest(tree: PointTree, k: int, own: np.ndarray | None = None,
            limit: float | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
    """The ``k + 1`` nearest points of each query, itself first, in blocks.

    Parameters
    ----------
    tree : PointTree
        Over the points (:func:`point_tree`).
    k : int
        Neighbours besides the point itself, ``0 <= k < n``.
    own : (m,) int ndarray, optional
        The points to query, by index (default: all of them, ``0 .. n - 1``).
    limit : float, optional
        Also say which neighbours lie within this distance.

    Returns
    -------
    neighbors : (m, k + 1) int32 ndarray (int64 from 2**31 points on)
        Column 0: the query itself; then its ``k`` nearest other points by (distance,
        index).
    kth : (m,) float64 ndarray
        The distance to the ``k``-th neighbour (the last column; 0 when ``k = 0``).
    within : (m, k) bool ndarray or None
        With ``limit``: ``distance <= limit`` for columns ``1 .. k``.

    Raises
    ------
    ValueError
        When ``k`` is negative or not below the number of points.

    Examples
    --------
    >>> pts = np.c_[np.arange(5.0), np.zeros(5), np.zeros(5)]
    >>> nbr, kth, within = nearest(point_tree(pts), 2, limit=1.5)
    >>> nbr[2].tolist(), kth.tolist(), within[0].tolist()
    ([2, 1, 3], [2.0, 1.0, 1.0, 1.0, 2.0], [True, False])
    """
    pts = tree.points
    n = pts.shape[0]
    if not 0 <= k < max(n, 1):
        raise ValueError(f"k = {k} neighbours of {n} points: need 0 <= k < {n}")
    own = np.arange(n, dtype=np.int64) if own is None else np.asarray(own, dtype=np.int64)
    m = own.shape[0]
    dtype = np.int32 if n < 2**31 else np.int64
    neighbors = np.empty((m, k + 1), dtype=dtype)
    kth = np.zeros(m)
    within = None if limit is None else np.empty((m, k), dtype=bool)
    if k == 0:
        neighbors[:, 0] = own
        return neighbors, kth, within
    query = native.kernel("nearest.nearest_in_tree")
    dist = np.empty((min(m, BLOCK), k + 1))
    for s in range(0, m, BLOCK):
        e = min(m, s + BLOCK)
        d = dist[:e - s]
        query(pts, tree.start, tree.end, tree.left, tree.boxes, own[s:e], k,
              neighbors[s:e], d)
        kth[s:e] = d[:, k]
        if within is not None:
            within[s:e] = d[:, 1:] <= limit
    return neighbors, kth, within
