"""The k nearest neighbours of each point (the point graph's first step).

:func:`point_tree` builds a tree over a cloud's distinct points in the Z-order of a local
frame (a binary radix tree of Z-order keys, node boxes of its points: about 7 bytes per
point, no copy of the points where they come in that order), and
:func:`nearest` queries it in one compiled loop, keeping only what the graph reads:
the neighbours as 4-byte indices, the distance to the ``k``-th and, with a radius, which
neighbours lie within it (44 + 8, and 10 more with a radius, bytes per point at ``k =
10``).

The keys are the points' coordinates as integers in a frame (from the lower corner of
the cloud's box, the same power-of-two scale on every axis: :func:`local_keys`), so the
cells split space alike along every axis wherever the cloud sits: a floor at ``z = 0``
(where the bits of a float spread a centimetre of noise over many binades) and survey
coordinates (UTM: x about 5e5, y about 5e6) are searched as fast as the same cloud near
the origin. :func:`~superfacets.elements.points.distinct_points` lists the points in
that order, and the tree takes them as they are; points in another order are copied
into it (24 bytes a point, and 16 for the maps between the orders).

Each point's neighbours are its ``k`` nearest other points in the order of (distance,
index), itself first: ties at any distance (quantized scans) go to the lowest index, the
index being the position's place in
:func:`~superfacets.elements.points.distinct_points`' order, so the answer is a function
of the positions alone, whatever the tree: a tile of a cloud
(:mod:`superfacets.scale.tiles.phases`) gets the whole cloud's neighbours inside its halo, and no
block size or thread count changes a bit of it. Distances are computed as scipy's KD-tree
computes them (the same neighbours and distances where no two are tied).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from .._kernels import native
from .._runtime.arrays import COMPILED_MIN
from ..checks import check_int
from ..errors import ParameterError
from ..inputs.bounds import column_bounds

__all__ = ["LEAF", "MAX_LEAF", "PointTree", "point_tree", "nearest", "closest", "local_keys",
           "local_frame", "key_window", "shared_prefix"]

#: Points per leaf of the tree (the 27 labelled scans and a 3M-point surface: 32 queries
#: the 10 and the 20 nearest 7-14 % faster than 16, 8 is 1.2 times slower than 16).
LEAF = 32
#: The most points a leaf may hold (a larger leaf is a slower tree, never a wrong one).
MAX_LEAF = 1 << 20


class PointTree(NamedTuple):
    """The tree of :func:`point_tree`: ``points`` are the cloud's points in the tree's
    order, ``ids[r]`` the index of row ``r`` in the cloud and ``rows`` the inverse (the row
    of each point), both None where the rows are the points; node ``v`` holds the rows
    ``start[v]:end[v]``, its children are ``left[v]`` and ``left[v] + 1`` (-1: a leaf), its
    box ``boxes[v]`` (lower corner, upper corner)."""

    points: np.ndarray
    start: np.ndarray
    end: np.ndarray
    left: np.ndarray
    boxes: np.ndarray
    ids: np.ndarray | None
    rows: np.ndarray | None


def shared_prefix(keys: np.ndarray) -> int:
    """The number of leading bits of the 189-bit key strings ``keys`` ((n, 3) uint64, 63
    bits a word) that every row shares (189 when all are equal or there is one row)."""
    shared = 0
    for w in range(3):
        # (the bits set in one key and clear in another: no temporary array)
        vary = int(np.bitwise_or.reduce(keys[:, w]) & ~np.bitwise_and.reduce(keys[:, w]))
        if vary:
            return shared + 63 - vary.bit_length()
        shared += 63
    return shared


def key_window(keys: np.ndarray, start: int) -> np.ndarray:
    """Bits ``start .. start + 63`` of each row's 189-bit key string (zeros past its end),
    as one uint64 (the first bit the highest); ``start`` an integer >= 0."""
    start = check_int("start", start, lo=0)
    if start >= 189:
        return np.zeros(keys.shape[0], dtype=np.uint64)
    if keys.shape[0] >= COMPILED_MIN and keys.flags.c_contiguous:  # one pass on threads
        out = np.empty(keys.shape[0], dtype=np.uint64)
        native.kernel("geometry.key_window")(keys, int(start), out)
        return out
    j, o = divmod(start, 63)
    out = (keys[:, j] & np.uint64((1 << (63 - o)) - 1)) << np.uint64(o + 1)
    if j < 2:
        out |= keys[:, j + 1] >> np.uint64(62 - o)
    return out


def local_keys(points: np.ndarray, frame: tuple[np.ndarray, float]) -> np.ndarray:
    """Z-order keys of ``points`` in a local frame.

    Parameters
    ----------
    points : (n, 3) float64 ndarray
    frame : (lo, scale)
        ``lo`` ((3,) float64) the frame's origin, ``scale`` its integers per unit
        (:func:`local_frame`).

    Returns
    -------
    (n, 3) uint64 ndarray
        Each coordinate as the integer ``floor((x - lo) * scale)`` (at most ``2**62``),
        interleaved x, y, z from the top, 63 bits a word.

    Examples
    --------
    >>> pts = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 1]])
    >>> k = local_keys(pts, local_frame(pts))
    >>> np.argsort(k[:, 0]).tolist()
    [0, 2, 1, 3]
    """
    pts = np.ascontiguousarray(points, dtype=np.float64)
    keys = np.empty((pts.shape[0], 3), dtype=np.uint64)
    lo, scale = frame
    native.kernel("geometry.local_morton_keys")(pts, np.asarray(lo, dtype=np.float64),
                                                float(scale), keys)
    return keys


def local_frame(points: np.ndarray, box: np.ndarray | None = None
                ) -> tuple[np.ndarray, float]:
    """The frame of :func:`local_keys` for ``points``: the lower corner of their box (or
    of ``box``, (2, 3): lower and upper corner, holding them), and ``2**62`` integers
    across the least power of two above its largest side (0 when it is one position):
    the Z-order's cells are then the halvings of a cube from that corner, and scaling
    by a power of two rounds nothing."""

    if box is not None:
        lo, hi = (np.asarray(c, dtype=np.float64) for c in box)
    elif not points.shape[0]:
        return np.zeros(3), 0.0
    else:
        lo, hi = column_bounds(points)
    with np.errstate(over="ignore"):  # (a side past the largest float: one cell)
        side = float(np.max(hi - lo))
    if not 0 < side < np.inf:
        return lo, 0.0
    return lo, math.ldexp(1.0, 62 - math.frexp(side)[1])  # (side < 2**frexp(side)[1])


def point_tree(points: np.ndarray, leaf: int = LEAF,
               frame: tuple[np.ndarray, float] | None = None) -> PointTree:
    """The search tree of distinct points in the Z-order of their own frame (see the
    module notes).

    Parameters
    ----------
    points : (n, 3) float64 ndarray
        Finite and distinct (:func:`~superfacets.elements.points.distinct_points`).
    leaf : int, default :data:`LEAF`
        Most points in a leaf, ``1 <= leaf <= MAX_LEAF``.
    frame : (lo, scale), optional
        The frame ``points`` are already ordered in (as
        :func:`~superfacets.elements.points.distinct_points` lists them): the tree takes
        them as they are. Default: the points' own frame (:func:`local_frame`), and
        the tree orders a copy of them.

    Returns
    -------
    PointTree

    Raises
    ------
    ParameterError
        If ``leaf`` is not an integer in ``1..MAX_LEAF``, or the points are not finite
        ``(n, 3)``.

    Examples
    --------
    >>> pts = np.c_[np.arange(40.0), np.zeros(40), np.zeros(40)] + [5e5, 5e6, 0]
    >>> tree = point_tree(pts)
    >>> bool((tree.points == pts[tree.ids]).all())
    True
    >>> bool((tree.ids[tree.rows] == np.arange(40)).all())
    True
    """

    leaf = check_int("leaf", leaf, lo=1, hi=MAX_LEAF)  # (0: a leaf never small enough)
    pts = np.ascontiguousarray(points, dtype=np.float64)
    if pts.ndim != 2 or pts.shape[1:] != (3,) or not np.isfinite(pts).all():
        raise ParameterError(f"points must be finite, of shape (n, 3), got {pts.shape}")
    n = pts.shape[0]
    ids = rows = None
    if frame is None:
        frame = local_frame(pts)
        keys = local_keys(pts, frame)
        window = key_window(keys, shared_prefix(keys))
        del keys
        ids, ordered = np.empty(n, dtype=np.int64), np.empty_like(window)
        native.kernel("geometry.sort_keys")(window, ids, ordered)  # (stable)
        del window, ordered
        pts = pts[ids]
        rows = np.empty(n, dtype=np.int64)
        rows[ids] = np.arange(n, dtype=np.int64)
    keys = local_keys(pts, frame)  # (in the tree's order: no copy of 24 bytes a point)
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
    return PointTree(pts, start, end, left, boxes, ids, rows)


def nearest(tree: PointTree, k: int, own: np.ndarray | None = None,
            limit: float | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
    """The ``k + 1`` nearest points of each query, itself first.

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
    if m and (int(own.min()) < 0 or int(own.max()) >= n):
        raise ValueError(f"own: a point outside 0..{n - 1}")
    dtype = np.int32 if n < 2**31 else np.int64
    neighbors = np.empty((m, k + 1), dtype=dtype)
    kth = np.zeros(m)
    within = None if limit is None else np.empty((m, k), dtype=bool)
    if k == 0:
        neighbors[:, 0] = own
        return neighbors, kth, within
    query = native.kernel("nearest.nearest_in_tree")
    ids = np.empty(0, dtype=np.int64) if tree.ids is None else tree.ids
    query(pts, tree.start, tree.end, tree.left, tree.boxes, ids,
          own if tree.rows is None else tree.rows[own], k,
          np.inf if limit is None else float(limit), neighbors, kth,
          np.empty((0, k), dtype=bool) if within is None else within)
    return neighbors, kth, within


def closest(tree: PointTree, queries: np.ndarray) -> np.ndarray:
    """The nearest point of the tree to each query position (any position, not one of the
    tree's points), ties to the lower index: a function of the positions alone.

    Parameters
    ----------
    tree : PointTree
        Over the points (:func:`point_tree`), at least one.
    queries : (m, 3) float ndarray
        Positions, in the points' units; finite.

    Returns
    -------
    (m,) int64 ndarray
        The index of each query's nearest point (its row in the points the tree was
        built from), by (squared distance, index).

    Raises
    ------
    ValueError
        When the tree holds no point, or a query is not finite or ``queries`` is not
        ``(m, 3)``.

    Examples
    --------
    >>> pts = np.c_[np.arange(5.0), np.zeros(5), np.zeros(5)]
    >>> closest(point_tree(pts), [[2.4, 1.0, 0.0], [0.5, 0.0, 0.0], [9.0, 0.0, 0.0]]).tolist()
    [2, 0, 4]
    """
    q = np.ascontiguousarray(queries, dtype=np.float64)
    if q.ndim != 2 or q.shape[1:] != (3,) or not np.isfinite(q).all():
        raise ValueError(f"queries must be finite, of shape (m, 3), got {q.shape}")
    if tree.points.shape[0] == 0:
        raise ValueError("no points to be nearest to")
    out = np.empty(q.shape[0], dtype=np.int64)
    if q.shape[0]:
        ids = np.empty(0, dtype=np.int64) if tree.ids is None else tree.ids
        native.kernel("nearest.closest_in_tree")(tree.points, tree.start, tree.end, tree.left,
                                                 tree.boxes, ids, q, out)
    return out
