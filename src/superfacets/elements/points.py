"""The point graph of a cloud: symmetric k-nearest neighbours, with per-point geometry.

The paper names point clouds as future work, "with a careful reformulation of
weights for adjacent elements". Here each point is an element:

- adjacency: ``i ~ j`` when either is among the other's ``n_neighbors``
  nearest (:mod:`superfacets.elements.neighbors`), optionally only within
  ``neighbor_radius`` (a fraction of the bounding-box diagonal ``d``); points
  at equal distances (quantized scans) go in the order of their index;
  the points are indexed along a Z-order curve of their coordinates as integers
  in the cloud's frame (its box's lower corner, one scale on every axis), so the
  order is as good at z = 0 or in survey coordinates as near the origin, and a
  box of a cloud given the whole cloud's frame (``PointCloud.frame``: a tiled
  run's tiles) lists its points in the whole cloud's order and gets the whole
  cloud's neighbours away from its edge (:mod:`superfacets.scale.tiles.phases`); a point
  whose neighbours lie on a line (a LiDAR scan line far from the sensor: linearity
  ``(l1 - l2) / l1`` of their covariance above :data:`LINEAR`) is also joined to its
  ``WIDEN * n_neighbors`` nearest, so that the graph spans the surface
  across scan lines instead of following each line alone;
- size: the area the point stands for, ``a_i = pi rho_i^2 / K`` with
  ``rho_i`` the distance to its ``K``-th neighbour (the k-nearest-neighbour
  density estimate on a surface), so the sizes add up to about the surface
  area and ``n_segments`` and ``radius`` mean what they mean on a mesh;
- normal (kept in float32: :data:`NORMALS_DTYPE`): given (trusted as oriented), or the
  PCA normal of the point and its ``K`` neighbours (smallest eigenvector of their covariance), then
  oriented consistently: towards the sensor when the viewpoint is known,
  else by propagation along a minimum spanning tree of flat steps (Hoppe et
  al. 1992; the one tree under the order (cost, lower end, higher end) of the edges)
  with each connected piece turned outwards (away from its mean), or, for
  an open surface seen from a known side (``PointCloud.up``: LAS files,
  z up), turned to agree with that direction; given an oriented sample
  (``PointCloud.orient_like``: a tiled run's), each normal is instead turned
  to agree with the sample's normal nearest its point.
  PCA's arbitrary signs therefore never reach the convexity test;
- weight terms as on mesh vertices: geodesic term ``|p_i - p_j|``, the angle
  of the normals scaled by that distance, concave when
  ``(n_i - n_j) . (p_i - p_j) < 0``;
- border length of an adjacency (connectivity, compactness): each point's
  cell taken as a disk of its area, the perimeter ``2 sqrt(pi a_i)`` shared
  among its neighbours: ``l_ij = (P_i / deg_i + P_j / deg_j) / 2``.
"""

from __future__ import annotations

from functools import partial
from typing import NamedTuple

import numpy as np

from .._kernels import native
from .._runtime.arrays import COMPILED_MIN, sorted_unique
from .._runtime.memory import give_back_free_memory
from ..checks import check_int, check_positive
from ..inputs.bounds import column_bounds, column_means
from ..inputs.cloud import PointCloud, as_cloud
from . import graph as _graph
from .graph import LAZY, ElementGraph, adjacency_csr, cached_on, pairs_from_csr
from .neighbors import key_window, local_frame, local_keys, nearest, point_tree, shared_prefix
from .normals import estimate_normals, normals_and_linearity, orient_normals
from .vertices import symmetric_terms

_TRIM_MIN = 1 << 18  # rows from which the build hands the allocator's free memory back

__all__ = ["point_graph", "kept_diagonal", "PointElements", "estimate_normals",
           "orient_normals", "distinct_points", "surface_neighbours", "STEP_CANDIDATES",
           "graph_key", "MAX_NEIGHBORS"]

#: Default number of nearest neighbours of the point graph.
DEFAULT_NEIGHBORS = 10
#: Largest number of nearest neighbours of the point graph.
MAX_NEIGHBORS = 100
#: The point graph keeps its normals in float32 (12 bytes per point less through the
#: whole run; the passes and the coarsening do not read them); what reads them computes
#: in float64 from these values. Judged with ``superfacets experiment`` on the 300
#: benchmark meshes' sampled clouds (``docs/notes/scale-design.md``).
NORMALS_DTYPE = np.float32
#: A point whose ``n_neighbors`` neighbours lie on a line (the linearity ``(l1 - l2) / l1``
#: of their covariance above this) ...
LINEAR = 0.95
#: ... is also joined to this many times ``n_neighbors`` nearest points: a scan line
#: (a LiDAR ring far from the sensor) then reaches the next one, as a surface's
#: neighbourhood should. 13-17 % of the points of two SemanticKITTI sweeps, none of an
#: airborne scan, 0.02 % of 20,000 points sampled on a mesh (docs/notes/superpoints.md,
#: "Scan lines").
WIDEN = 2


class PointElements(NamedTuple):
    """The point graph of a cloud and the element of each point.

    Attributes
    ----------
    graph : ElementGraph
        ``kind = "points"``, one element per distinct valid point.
    index : (N,) int32 ndarray (int64 from ``2**31`` rows)
        Element of each row of the cloud: -1 for invalid points; exact
        duplicates share one element.
    """

    graph: ElementGraph
    index: np.ndarray


def distinct_points(p: np.ndarray, frame: tuple[np.ndarray, float] | None = None
                    ) -> tuple[np.ndarray, np.ndarray]:
    """The distinct positions of a cloud in Z-order, and the one of each input row.

    The order is the Z-order of the positions as integers in a frame
    (:func:`~superfacets.elements.neighbors.local_keys`): given the same frame,
    any subset of a cloud (a tile's box) lists its points in the same relative
    order as the whole cloud; the frame's cells are cubes wherever the cloud
    sits (at 0, in survey coordinates), so neighbours in space are near in the
    list and the graph's kernels read memory in order (``docs/notes/code-measurements.md``).

    Parameters
    ----------
    p : (n, 3) float ndarray
        Finite positions.
    frame : (lo, scale), optional
        The frame (:func:`~superfacets.elements.neighbors.local_frame`); default the
        positions' own.

    Returns
    -------
    points : (m, 3) float64 ndarray
        The distinct positions (``-0.0`` and ``0.0`` are one), ``m <= n``.
    inverse : (n,) int64 ndarray
        Index into ``points`` of each row: ``points[inverse]`` equals ``p``.

    Examples
    --------
    >>> pts, inv = distinct_points(np.array([[1.5, 1, 1], [1.0, 1, 1], [1.5, 1, 1]]))
    >>> pts.tolist(), inv.tolist()
    ([[1.0, 1.0, 1.0], [1.5, 1.0, 1.0]], [1, 0, 1])
    """
    distinct_in_order = native.kernel("geometry.distinct_in_order")
    sort_keys = native.kernel("geometry.sort_keys")

    p = np.ascontiguousarray(p, dtype=np.float64)
    keys = local_keys(p, local_frame(p) if frame is None else frame)
    window = key_window(keys, shared_prefix(keys))
    # a stable sort (on threads where compiled: numpy's argsort of 10M keys takes 2.7 s),
    # then equal windows by the whole keys and the coordinates
    order, ordered = np.empty(p.shape[0], dtype=np.int64), np.empty_like(window)
    sort_keys(window, order, ordered)
    del window
    native.kernel("geometry.order_ties")(order, ordered, keys, p)
    del ordered, keys
    out = np.empty_like(p)
    inverse = np.empty(p.shape[0], dtype=np.int64)
    m = distinct_in_order(p, order, out, inverse)
    return out[:m].copy() if m < p.shape[0] else out, inverse


def point_graph(cloud, n_neighbors: int = DEFAULT_NEIGHBORS,
                neighbor_radius: float | None = None, *, oriented: bool = True,
                step: float = 1.0) -> PointElements:
    """The point graph of a cloud (see the module notes).

    Built on the first call for each neighbourhood and kept with the cloud
    (later calls with the same ``n_neighbors`` and ``neighbor_radius`` return
    the same object).

    Parameters
    ----------
    cloud : PointCloud
        Usable (:meth:`~superfacets.inputs.cloud.PointCloud.check_usable`).
    n_neighbors : int, default 10
        Nearest neighbours of each point, ``1 ..`` :data:`MAX_NEIGHBORS` (fewer when the
        cloud has fewer points).
    neighbor_radius : float, optional
        Drop neighbours farther than this fraction of the bounding-box diagonal (``> 0``).
    oriented : bool, default True
        False: estimated normals keep the signs PCA gives them (no propagation), for a
        caller that reads only the adjacency, sizes and border lengths (the same as
        oriented: the tiled runs' connectivity repair); about a third of the build's
        time on a cloud. The oriented graph, if already built, is returned.
    step : float, default 1
        ``> 1``: each point's neighbours are the ``n_neighbors`` of its
        :data:`STEP_CANDIDATES` times as many nearest whose offset ``d`` is shortest with
        its part along the point's normal (PCA of its ``n_neighbors`` nearest) weighed
        ``step`` times, ``|d|^2 + (step^2 - 1) (n . d)^2``: points on its own surface
        before those across a step (``step_weight``, not in the paper). Its size is read
        at the farthest of them. Kept apart from the plain graph (1).

    Returns
    -------
    PointElements

    Raises
    ------
    TypeError
        If ``cloud`` is no cloud :func:`superfacets.as_cloud` takes (an ``(N, 3)`` array is
        taken as a cloud of its own, its graph not kept).
    InvalidCloudError
        If the cloud cannot be segmented.
    ParameterError
        If ``n_neighbors`` or ``neighbor_radius`` is out of its range.

    Examples
    --------
    >>> xy = np.stack(np.meshgrid(np.arange(10.0), np.arange(10.0)), -1).reshape(-1, 2)
    >>> g = point_graph(PointCloud(np.c_[xy, np.zeros(100)]), 4).graph
    >>> g.n_elements, round(float(np.abs(g.normals[:, 2]).min()), 6)
    (100, 1.0)
    """
    n_neighbors = check_int("n_neighbors", n_neighbors, lo=1, hi=MAX_NEIGHBORS)
    if neighbor_radius is not None:
        neighbor_radius = check_positive("neighbor_radius", neighbor_radius)
    if not isinstance(cloud, PointCloud):  # an array, trimesh's or Open3D's cloud
        cloud = as_cloud(cloud)
    graphs = cached_on(cloud, "_point_graphs", dict)
    key = graph_key(n_neighbors, neighbor_radius, step)
    if not oriented and key not in graphs:  # (the oriented graph, where kept, serves)
        key += ("unoriented",)
    if key not in graphs:
        graphs[key] = _build_point_graph_of(cloud, n_neighbors, neighbor_radius, oriented,
                                            step)
    return graphs[key]


def graph_key(n_neighbors: int, neighbor_radius: float | None = None,
              step: float = 1.0) -> tuple:
    """The key a cloud keeps its point graph under (:func:`point_graph`): the
    neighbourhood, and ``step`` where it is not 1.

    Examples
    --------
    >>> graph_key(10), graph_key(10, None, 4)
    ((10, None), (10, None, ('step', 4.0)))
    """
    return (n_neighbors, neighbor_radius) + (() if step == 1 else (("step", float(step)),))


def kept_diagonal(cloud) -> float | None:
    """The bounding-box diagonal of a cloud's valid points, read on a point graph already
    built for it (:func:`point_graph`, any neighbourhood: the same points), else None.

    The graph's distinct points have the bounds of the valid rows, so the same diagonal,
    without giving back the points the build lent (24 bytes a point, and a pass).

    Parameters
    ----------
    cloud : PointCloud

    Returns
    -------
    float or None
        In the cloud's units.

    Examples
    --------
    >>> cloud = PointCloud(np.array([[0.0, 0, 0], [3, 4, 0], [3, 0, 0], [0, 4, 0]]))
    >>> kept_diagonal(cloud), float(point_graph(cloud, 2).graph.diagonal), kept_diagonal(cloud)
    (None, 5.0, 5.0)
    """
    graphs = cloud.__dict__.get("_point_graphs")
    return float(next(iter(graphs.values())).graph.diagonal) if graphs else None


#: ``step_weight``: each point's neighbours are chosen among this many times
#: ``n_neighbors`` nearest (2: on 27 labelled scans 91 of 108 targets met in 1.19 times the
#: run's time; 1.5: 90 in less time, but two floors closer than 1.3 times the points'
#: spacing then keep points of the other floor among their ten).
STEP_CANDIDATES = 2
_STEP_BLOCK = 1 << 16


def surface_neighbours(pts: np.ndarray, tree, k: int, step: float,
                       limit: float | None = None) -> tuple:
    """Each point's ``k`` neighbours along its surface: of its ``STEP_CANDIDATES * k``
    nearest, the ``k`` whose offset ``d`` has the least ``|d|^2 + (step^2 - 1) (n . d)^2``
    (ties: the lower index), ``n`` the normal of its ``k`` nearest (PCA).

    Parameters
    ----------
    pts : (n, 3) float64 ndarray
    tree : PointTree
        Over ``pts`` (:func:`~superfacets.elements.neighbors.point_tree`).
    k : int
        ``>= 3``, below ``n - 1``.
    step : float
        ``> 1``.
    limit : float, optional
        As :func:`~superfacets.elements.neighbors.nearest`.

    Returns
    -------
    neighbors : (n, k + 1) int ndarray
        Column 0 the point itself, then its neighbours by that distance.
    kth : (n,) float64 ndarray
        The distance to the farthest of them.
    within : (n, k) bool ndarray or None
        With ``limit``: which of them lie within it.

    Raises
    ------
    ValueError
        As :func:`~superfacets.elements.neighbors.nearest`.

    Examples
    --------
    >>> xy = np.stack(np.meshgrid(np.arange(9.0), np.arange(9.0)), -1).reshape(-1, 2)
    >>> two = np.r_[np.c_[xy, np.zeros(81)], np.c_[xy, np.full(81, 0.9)]]  # a step of 0.9
    >>> upper = np.arange(162) >= 81
    >>> def across(nbr):  # neighbours listed on the other floor
    ...     return int((upper[nbr[:, 1:]] != upper[:, None]).sum())
    >>> tree = point_tree(two)
    >>> across(nearest(tree, 4)[0]), across(surface_neighbours(two, tree, 4, 4.0)[0])  # edges
    (170, 16)
    """
    kc = int(min(STEP_CANDIDATES * k, pts.shape[0] - 1))
    cand, _, keep_c = nearest(tree, kc, limit=limit)
    n = pts.shape[0]
    if cand.dtype != np.int32:  # (2**31 points or more: in blocks, numpy's)
        normals = estimate_normals(pts, np.ascontiguousarray(cand[:, :k + 1]))
        return _surface_neighbours_numpy(pts, cand, keep_c, normals, k, step)
    nbr = np.empty((n, k + 1), dtype=np.int32)
    kth = np.empty(n)
    pick = np.empty((n if keep_c is not None else 0, k), dtype=np.int32)
    # (the normals of the first k + 1 candidates computed in the same pass: no copy)
    native.kernel("nearest.surface_select")(np.ascontiguousarray(pts), cand, int(k),
                                            float(step), nbr, kth, pick)
    keep = None if keep_c is None else np.take_along_axis(keep_c, pick - 1, 1)
    return nbr, kth, keep


def _surface_neighbours_numpy(pts, cand, keep_c, normals, k: int, step: float) -> tuple:
    """:func:`surface_neighbours`' choice in numpy, in blocks of rows (int64 neighbours)."""
    n = pts.shape[0]
    nbr = np.empty((n, k + 1), dtype=cand.dtype)
    kth = np.empty(n)
    keep = None if keep_c is None else np.empty((n, k), dtype=bool)
    grow = step * step - 1.0
    for b0 in range(0, n, _STEP_BLOCK):
        b1 = min(n, b0 + _STEP_BLOCK)
        c = cand[b0:b1, 1:]
        d = pts[c] - pts[cand[b0:b1, 0]][:, None, :]
        d2 = (d[..., 0] * d[..., 0] + d[..., 1] * d[..., 1]) + d[..., 2] * d[..., 2]
        nr = normals[cand[b0:b1, 0]]
        off = (d[..., 0] * nr[:, None, 0] + d[..., 1] * nr[:, None, 1]) + d[..., 2] * nr[:, None, 2]
        order = np.lexsort((c, d2 + grow * (off * off)), axis=1)[:, :k]
        nbr[b0:b1, 0] = cand[b0:b1, 0]
        nbr[b0:b1, 1:] = np.take_along_axis(c, order, 1)
        kth[b0:b1] = np.sqrt(np.take_along_axis(d2, order, 1).max(axis=1))
        if keep is not None:
            keep[b0:b1] = np.take_along_axis(keep_c[b0:b1], order, 1)
    return nbr, kth, keep


def _normals_and_linearity(cloud, pts, nbr, index, valid):
    """Each distinct point's normal (the cloud's own, of its first row, where it has them;
    else PCA of the k neighbours) and how much its neighbourhood is a line (a scan line)."""
    if cloud.normals is None:
        return normals_and_linearity(pts, nbr)
    pca_linearity = native.kernel("normals.pca_linearity")

    n = pts.shape[0]
    first = np.full(n, -1, dtype=np.int64)
    first[index[valid][::-1]] = valid[::-1]  # the first row of each distinct point
    normals = np.ascontiguousarray(cloud.normals[first])
    linearity = np.empty(n)
    pca_linearity(np.ascontiguousarray(pts), nbr, linearity)
    return normals, linearity


def _build_point_graph_of(cloud, n_neighbors: int, neighbor_radius: float | None,
                          oriented: bool = True, step: float = 1.0) -> PointElements:
    valid = np.flatnonzero(cloud.valid)
    n_rows = cloud.n_total
    given = cloud.points if valid.shape[0] == n_rows else cloud.points[valid]
    frame = local_frame(given, cloud.frame)  # (a tile's: the whole cloud's)
    pts, inverse = distinct_points(given, frame)
    del given
    index = np.full(n_rows, -1, dtype=np.int32 if n_rows < 2**31 else np.int64)
    index[valid] = inverse
    del inverse
    # the cloud's points, where it alone holds them (read from a file), kept as the
    # distinct points and each row's index until asked for: 24 bytes per point less
    cloud.lend_points(pts, index)
    if n_rows >= _TRIM_MIN:  # the Z-order's freed temporaries kept
        give_back_free_memory()  # by the allocator's heap would add to the build's peak
    n = pts.shape[0]
    k = int(min(n_neighbors, n - 1))
    lower, upper = column_bounds(pts)
    diagonal = float(np.linalg.norm(upper - lower))
    # a tree of the points' Z-order (distinct_points): ranges of rows, no copy of them
    tree = point_tree(pts, frame=frame)
    limit = None if neighbor_radius is None else neighbor_radius * diagonal
    # column 0: the point itself; 4-byte indices, queried in blocks (elements/neighbors.py)
    if step != 1 and k >= 3 and n > k + 1:  # (not in the paper) neighbours along the surface
        nbr, kth, keep = surface_neighbours(pts, tree, k, step, limit)
    else:
        nbr, kth, keep = nearest(tree, k, limit=limit)
    area = np.pi * kth ** 2 / k
    del kth
    positive = area > 0
    if not positive.all():  # cannot happen with distinct points; keep sizes > 0 anyway
        area[~positive] = area[positive].min() if positive.any() else 1.0

    normals, linearity = _normals_and_linearity(cloud, pts, nbr, index, valid)
    wide = np.flatnonzero(linearity > LINEAR)
    del linearity
    k_wide = int(min(WIDEN * k, n - 1))
    if k_wide <= k:
        wide = wide[:0]
    more = np.zeros((0, 1), dtype=nbr.dtype)
    more_keep = np.zeros((0, 1), dtype=bool)
    if wide.size:
        more, _, more_keep = nearest(tree, k_wide, wide, limit)
        more = more[:, 1:]
        if more_keep is None:
            more_keep = np.ones(more.shape, dtype=bool)
    del tree  # (its nodes, before the layout's peak)

    cand = nbr[:, 1:]  # read in place by the kernel (a copy costs more than it saves)
    pair_dtype = np.int32
    if _graph.adjacency_dtype(2 * (cand.size + more.size)) == np.int32:  # the kernel's layout
        knn_csr = native.kernel("adjacency.knn_csr")
        if keep is None:  # every neighbour listed: no mask (10 bytes per point at the peak)
            keep = np.zeros((0, cand.shape[1]), dtype=bool)

        indptr = np.empty(n + 1, dtype=np.int64)
        # i ~ j if either lists the other
        indices = knn_csr(cand, keep, indptr, wide, more, more_keep)
        del more, more_keep, nbr, cand, keep
        indices = _shrunk(indices, int(indptr[n]))  # (the lists let go first)
    else:  # the distinct pairs, sorted
        if keep is None:
            keep = np.ones(cand.shape, dtype=bool)
        src = np.concatenate([np.repeat(np.arange(n), k).reshape(n, k)[keep],
                              np.repeat(wide, more.shape[1]).reshape(more.shape)[more_keep]])
        dst = np.concatenate([cand[keep], more[more_keep]]).astype(np.int64)
        src, dst = src[src != dst], dst[src != dst]  # (no point is its own neighbour)
        key = np.minimum(src, dst) * np.int64(n) + np.maximum(src, dst)
        del src, dst
        key = sorted_unique(key)
        indptr, indices, _ = adjacency_csr(key // n, key % n, n)
        pair_dtype = np.int64
        del key, more, more_keep, nbr, cand, keep

    if cloud.normals is None and oriented:
        normals = orient_normals(pts, normals, indptr, indices, cloud.viewpoint,
                                 getattr(cloud, "orient_like", None),
                                 getattr(cloud, "up", None))
    normals = normals.astype(NORMALS_DTYPE)  # (kept through the run; read in float64)
    return point_elements(pts, area, normals, indptr, indices, index, pair_dtype,
                          lower=lower, diagonal=diagonal)


def point_elements(pts: np.ndarray, area: np.ndarray, normals: np.ndarray,
                   indptr: np.ndarray, indices: np.ndarray, index: np.ndarray,
                   pair_dtype=np.int32, *, lower: np.ndarray | None = None,
                   diagonal: float | None = None) -> PointElements:
    """The point graph of its arrays as :func:`point_graph` builds them (also read back
    from files: :mod:`superfacets.scale.tiles.graphs`).

    Parameters
    ----------
    pts : (n, 3) float64 ndarray
        The distinct points, in Z-order.
    area : (n,) float64 ndarray
    normals : (n, 3) ndarray
        In :data:`NORMALS_DTYPE`, oriented.
    indptr : (n + 1,) int64 ndarray
    indices : (2 e,) int32 or int64 ndarray
        The CSR adjacency.
    index : (N,) int32 or int64 ndarray
        Element of each row of the cloud, -1 for an invalid row.
    pair_dtype : numpy dtype, default int32
        Of the pairs, built when read.
    lower, diagonal : optional
        The points' lowest corner and bounding-box diagonal, if known.

    Returns
    -------
    PointElements
    """
    if lower is None or diagonal is None:
        lower, upper = column_bounds(pts)
        diagonal = float(np.linalg.norm(upper - lower))
    # the pairs, dual-edge map, spans and border lengths (about 180 bytes per point) are
    # built only if read: a default run reads the CSR layout and the border shares alone
    # (the weights: superfacets.method.weights.csr_point_weights)
    rebuild = dict.fromkeys(("pairs", "dual_edge"),
                            partial(pairs_from_csr, pair_dtype=pair_dtype))
    # the shares from the sizes as built (a run may stretch the sizes: adaptive density),
    # made again after a release (the passes do not read them: 8 bytes per point)
    rebuild["border_shares"] = partial(_shares, area)
    graph = ElementGraph(
        kind="points", positions=pts, sizes=area, normals=normals,
        centroid=column_means(pts), lower=lower, diagonal=diagonal, pairs=LAZY,
        indptr=indptr, indices=indices, dual_edge=LAZY, lengths=LAZY,
        boundary_elements=np.zeros(0, np.int64), boundary_lengths=np.zeros(0),
        spans=LAZY, border_shares=LAZY, terms_of=symmetric_terms,
        rebuild={**rebuild, "spans": _spans, "lengths": _lengths})
    return PointElements(graph, index)


def _shrunk(a: np.ndarray, size: int) -> np.ndarray:
    """The first ``size`` entries of a 1-D array the caller alone holds: the array itself,
    shrunk in place where numpy owns its memory (no copy: the tail is given back), else a
    copy."""
    if a.shape[0] == size:
        return a
    try:
        a.resize(size, refcheck=False)
        return a
    except ValueError:  # memory numpy does not own (a numba kernel's array)
        return a[:size].copy()


def _shares(area: np.ndarray, graph: ElementGraph) -> dict:
    """``rebuild["border_shares"]`` of a point graph: each point's share of the perimeter
    of its disk of area ``area`` (the sizes as built), ``2 sqrt(pi a_i) / deg_i``."""
    indptr = graph.indptr
    if (area.shape[0] >= COMPILED_MIN and indptr.dtype == np.int64 and area.dtype == np.float64
            and indptr.flags.c_contiguous and area.flags.c_contiguous):
        out = np.empty(area.shape[0])  # (the same values, one pass on threads)
        native.kernel("geometry.border_shares")(indptr, area, out)
        return {"border_shares": out}
    degree = np.diff(indptr).astype(np.float64)
    return {"border_shares": 2.0 * np.sqrt(np.pi * area) / np.maximum(degree, 1.0)}


def _spans(graph: ElementGraph) -> dict:
    """``rebuild["spans"]`` of a point graph: the spans again, as built."""
    return {"spans": _edge_spans(graph.positions, graph.pairs)}


def _lengths(graph: ElementGraph) -> dict:
    """``rebuild["lengths"]`` of a point graph: each pair's border length from the two
    shares (see the module notes): ``(share_lo + share_hi) / 2``."""
    pairs, shares = graph.pairs, graph.border_shares
    return {"lengths": 0.5 * (shares[pairs[:, 0]] + shares[pairs[:, 1]])}


def _edge_spans(pts: np.ndarray, pairs: np.ndarray) -> np.ndarray:
    """``|p_hi - p_lo|`` of each pair, as ``np.linalg.norm`` computes it."""
    edge_lengths = native.kernel("geometry.edge_lengths")

    spans = np.empty(pairs.shape[0])
    edge_lengths(pts, pairs, spans)
    return spans
