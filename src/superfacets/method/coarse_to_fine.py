"""Coarse-to-fine: solve on a coarsened element graph, then refine on the full one.

On a fine mesh (tens of thousands of elements per superfacet) the passes of
the method spend their time re-expanding whole windows for centers that move
by one element at a time. :func:`coarsen` groups the elements into clusters
of about ``ratio`` elements, so the iteration can first run on a graph
``ratio`` times smaller; the full graph then starts from centers that are
already where the coarse run settled, and needs few passes.

The clusters are the Voronoi cells, in the weighted element graph, of seeds
spread over the surface (one per occupied cell of a grid of the right
pitch): each element goes to its nearest seed by the method's own distance,
so a cell rarely straddles a concave crease (crossing it costs what it costs
the superfacets). The coarse graph joins two clusters when two of their
elements are adjacent; its weight is the shortest path between the two seeds
through that border, ``min (d_i + w_ij + d_j)`` over the adjacent pairs
``(i, j)``, with ``d`` the distance of each element to its seed, so coarse
distances follow the fine ones (never shorter) and keep the crease costs.
A cluster's position is the size-weighted mean of its elements' positions,
its size their total size and its normal their size-weighted mean normal.

``docs/notes/method.md`` (section "Coarse-to-fine") and ``docs/notes/benchmarks.md``
give the measurements behind the defaults.
"""

from __future__ import annotations

import math
from functools import partial
from typing import Callable, NamedTuple

import numpy as np

from .._kernels import native
from .._runtime.arrays import real_rows
from ..elements.graph import LAZY, ElementGraph, adjacency_csr, pairs_from_csr
from ..elements.kinds import kind_of
from ..inputs.bounds import column_bounds
from . import passes
from .classify import make_classifier
from .expansion import Workspaces, bucket_width
from .initialization import initial_centers
from .params import superfacet_measure
from .passes import update_centers
from .weights import HeldWeights, weights_array


def _voronoi(name: str):
    """A compiled Voronoi kernel."""
    return native.kernel(f"voronoi.{name}")


_MIN_CLUSTERS = 4  # clusters per superfacet below which the coarse run is not done
_MAX_RATIO_DIV = 8  # coarsen is capped at n / (8 k): clusters per superfacet

__all__ = ["COARSENING_READS", "Coarsening", "coarsen", "coarse_centers", "coarse_ratio",
           "coarsening_for", "grid_seeds", "start_centers", "voronoi_cells"]

#: The fields of a graph's :attr:`~superfacets.elements.graph.ElementGraph.rebuild` that
#: :func:`coarsen` reads (besides the CSR layout, positions and sizes, never released):
#: the others (pairs, dual edges, spans) may be released before it.
COARSENING_READS = ("normals", "lengths")


class Coarsening(NamedTuple):
    """A coarsened element graph and its map to the fine one.

    Attributes
    ----------
    graph : ElementGraph
        The clusters as elements (``kind`` that of the fine graph).
    weights : (2 e_c,) float64 ndarray
        Weight of each CSR entry of ``graph`` (see the module notes).
    cluster : (n,) int32 ndarray (int64 from ``2**31 - 1`` elements)
        Cluster of each fine element, ``0..n_c-1``.
    seeds : (n_c,) int64 ndarray
        The fine element each cluster grew from.
    """

    graph: ElementGraph
    weights: np.ndarray
    cluster: np.ndarray
    seeds: np.ndarray


def coarse_ratio(n_elements: int, k: int, kind: str = "faces", n_neighbors: int = 10) -> int:
    """Elements per cluster for ``k`` superfacets on ``n_elements``: 1 (no
    coarsening) below :data:`COARSE_MIN_PER_SEGMENT` elements per superfacet,
    else what leaves about :data:`COARSE_PER_SEGMENT` per superfacet. Points
    (``kind='points'``): from :data:`COARSE_MIN_PER_SEGMENT_POINTS`, leaving
    about :data:`COARSE_PER_SEGMENT_POINTS`, at most ``n_neighbors // 2``."""
    profile = kind_of(kind)
    per = n_elements / max(k, 1)
    if per < profile.coarse_min_per_segment:
        return 1
    ratio = int(per // profile.coarse_per_segment)
    return max(1, min(ratio, n_neighbors // 2)) if profile.coarse_neighbor_cap else ratio


def grid_seeds(positions: np.ndarray, area: float, n_target: int) -> np.ndarray:
    """About ``n_target`` elements spread over a surface: the lowest-index
    element of each occupied cell of a regular grid.

    The pitch is ``sqrt(area / n_target)``: a surface of area ``A`` crosses
    about ``A / h^2`` (up to ~1.7x, by its slope) cells of pitch ``h``.

    Parameters
    ----------
    positions : (n, 3) float64 ndarray
    area : float
        Total size of the elements (squared mesh units).
    n_target : int

    Returns
    -------
    (n_c,) int64 ndarray
        Element indices, ascending.
    """
    n = positions.shape[0]
    if n_target >= n or area <= 0:
        return np.arange(n, dtype=np.int64)
    h = math.sqrt(area / max(n_target, 1))
    lo, hi = column_bounds(positions)
    dims = np.floor((hi - lo) / h).astype(np.int64) + 1
    if int(dims[0]) * int(dims[1]) * int(dims[2]) < 2**62:
        cap = 1 << max(10, int(4 * n_target + 1).bit_length())
        while True:  # a hash table of cells, grown until at most half full
            first = _voronoi("first_in_cells")(positions, lo, h, dims, cap)
            if first.shape[0] or cap >= 4 * n:
                break
            cap *= 4
    if int(dims[0]) * int(dims[1]) * int(dims[2]) >= 2**62 or not first.shape[0]:
        cell = np.floor((positions - lo) / h).astype(np.int64)  # too many cells to hash
        first = np.unique(cell, axis=0, return_index=True)[1]
    return np.sort(first).astype(np.int64)


def voronoi_cells(graph: ElementGraph, csr_w: np.ndarray, seeds: np.ndarray
                  ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Each element's nearest seed in the weighted graph, and its distance.

    Connected components without a seed get seeds of their own (by
    :func:`grid_seeds` on their elements, at the same pitch).

    Returns
    -------
    seeds : (n_c,) int64 ndarray
        ``seeds`` followed by the added ones.
    cluster : (n,) int32 ndarray (int64 from ``2**31 - 1`` elements)
        Index into ``seeds`` of each element's nearest seed.
    dist : (n,) float64 ndarray
        Its distance (weights' units).
    """
    n = graph.n_elements
    inv_width, nb = bucket_width(csr_w)
    bound = graph.indices.shape[0] + n + 1
    # label-correcting: stale entries stay queued until popped (measured: up to 1.35 n
    # nodes in use on sampled clouds); pages of the queue are touched only once used
    cap = min(bound, max(1 << 14, 2 * n))
    head = np.full(nb, -1, dtype=np.int64)
    n_target = seeds.shape[0]
    while True:  # until the queue was large enough
        dist = np.full(n, np.inf)
        label = np.full(n, -1, dtype=np.int32 if n < 2**31 - 1 else np.int64)
        queue = (np.empty(cap, dtype=np.int32), np.empty(cap), np.empty(cap, dtype=np.int32),
                 head)
        all_seeds, first, full = seeds, 0, False
        nearest_seed = _voronoi("nearest_seed")
        while True:
            if nearest_seed(graph.indptr, graph.indices, csr_w, all_seeds, first, dist, label,
                            queue, inv_width) != 0:
                full = True
                break
            left = np.flatnonzero(label < 0)
            if left.shape[0] == 0:
                break
            more = left[grid_seeds(graph.positions[left], float(graph.sizes[left].sum()),
                                   max(1, n_target * left.shape[0] // n))]
            all_seeds, first = np.concatenate([all_seeds, more]), all_seeds.shape[0]
        if not full:
            return all_seeds, label, dist
        cap = min(bound, 4 * cap)


def coarsen(graph: ElementGraph, csr_w, ratio: int) -> Coarsening:
    """Group the elements of ``graph`` into clusters of about ``ratio`` elements.

    Reads the graph's CSR layout, positions, sizes, normals and border lengths, not
    its pairs (the pipeline releases those first: :meth:`ElementGraph.release`).

    Parameters
    ----------
    graph : ElementGraph
    csr_w : (2 e,) float64 ndarray or HeldWeights
        Weight of each CSR entry, ``>= 0``; a :class:`~superfacets.method.weights.
        HeldWeights` is let go once the clusters' adjacency is read from it.
    ratio : int
        Elements per cluster wanted (``>= 2``).

    Returns
    -------
    Coarsening
    """
    held, csr_w = csr_w, weights_array(csr_w)
    n = graph.n_elements
    positions = np.ascontiguousarray(graph.positions, dtype=np.float64)
    seeds = grid_seeds(positions, graph.area, max(1, n // ratio))
    seeds, cluster, dist = voronoi_cells(graph, csr_w, seeds)
    n_c = seeds.shape[0]

    # coarse adjacency first (its weights read the distances, let go before the clusters'
    # means are made): the fine pairs whose elements lie in different clusters (the
    # shortest seed-to-seed path through one); their summed border lengths only if read
    # (the coarse run does not: _coarse_lengths, the same sums)
    none = np.empty(0)
    pairs, w_c, _ = _voronoi("coarse_pairs")(graph.indptr, graph.indices, cluster, dist,
                                             csr_w, none, none, n_c)
    del dist, csr_w
    if isinstance(held, HeldWeights):  # (the fine weights: not read again before the passes)
        held.let_go()
    indptr, indices, dual_edge = adjacency_csr(pairs[:, 0], pairs[:, 1], n_c)
    # the coarse run reads the CSR layout: its pairs and dual-edge map are built again
    # (the same: the pairs are in (lo, hi) order) only if something asks
    del pairs
    weights = np.ascontiguousarray(w_c[dual_edge])
    del w_c, dual_edge
    tot, pos, nor, scale2 = _cluster_means(graph, positions, cluster, seeds)
    coarse = ElementGraph(
        kind=graph.kind, positions=pos, sizes=tot, normals=nor, centroid=graph.centroid,
        lower=graph.lower, diagonal=graph.diagonal, pairs=LAZY, indptr=indptr,
        indices=indices, dual_edge=LAZY, lengths=LAZY,
        boundary_elements=np.empty(0, dtype=np.int64), boundary_lengths=np.empty(0),
        scale2=scale2,
        rebuild={**dict.fromkeys(("pairs", "dual_edge"),
                                 partial(pairs_from_csr, pair_dtype=np.int64)),
                 "lengths": partial(_coarse_lengths, graph, cluster)})
    return Coarsening(graph=coarse, weights=weights, cluster=cluster, seeds=seeds)


def _coarse_lengths(fine: ElementGraph, cluster: np.ndarray, coarse: ElementGraph) -> dict:
    """The clusters' border lengths, made when first read: the lengths of the fine
    adjacencies joining each pair of clusters, summed in the fine graph's order
    (``voronoi.coarse_lengths``: ``coarse_pairs``' sums, bit for bit)."""
    pairs = np.ascontiguousarray(coarse.pairs, dtype=np.int32)
    return {"lengths": _voronoi("coarse_lengths")(fine.indptr, fine.indices, cluster, pairs,
                                                  *fine.border_arrays(), coarse.n_elements)}


def _cluster_means(graph: ElementGraph, positions: np.ndarray, cluster: np.ndarray,
                   seeds: np.ndarray) -> tuple:
    """Each cluster's total size, size-weighted mean position and (unit) mean normal, and
    its size-weighted mean squared scale (None where the graph has no scales); a cluster
    of zero size takes its seed's position (the sums ``np.bincount(cluster, weights=sizes
    * x[:, a])`` makes, in one compiled pass)."""
    n_c = seeds.shape[0]
    sizes = graph.sizes
    tot, pos, nor = np.zeros(n_c), np.zeros((n_c, 3)), np.zeros((n_c, 3))
    native.kernel("geometry.label_sums")(
        cluster, np.ascontiguousarray(sizes, dtype=np.float64), positions,
        real_rows(graph.normals), tot, pos, nor)
    safe = np.where(tot > 0, tot, 1.0)
    pos /= safe[:, None]
    scale2 = None  # content-sensitive runs: the clusters' size-weighted mean scale
    if graph.scale2 is not None:
        scale2 = np.bincount(cluster, weights=sizes * graph.scale2, minlength=n_c) / safe
        scale2[tot <= 0] = graph.scale2[seeds[tot <= 0]]
    empty = tot <= 0  # zero-size clusters: the seed's own position
    pos[empty] = positions[seeds[empty]]
    norm = np.linalg.norm(nor, axis=1)
    nor /= np.where(norm > 0, norm, 1.0)[:, None]
    return tot, pos, nor, scale2


def coarse_centers(graph: ElementGraph, csr_w: np.ndarray, ratio: int, *, init: str,
                   k: int | None, radius: float, window: float, assignment: str,
                   max_iter: int, tol: float, min_move: float, n_threads: int,
                   every_piece: bool = False,
                   on_coarsened: Callable[[], None] | None = None) -> tuple[np.ndarray, dict]:
    """Run the method on the graph coarsened by ``ratio``; return fine centers.

    The coarse run is the method itself (same initialization, window,
    assignment, ``tol`` and ``min_move``) on the clusters of :func:`coarsen`;
    its labels are carried to the fine elements, and the center of each
    superfacet is the fine element nearest its size-weighted mean (the center
    update of paper section 3.1, step 3, on the fine elements). ``every_piece``
    as in :func:`superfacets.method.initialization.initial_centers` (clusters never
    span two pieces, so the coarse graph has the same pieces).

    Returns
    -------
    centers : (K,) int64 ndarray or None
        Fine element indices, distinct, in the order of the coarse superfacets;
        None when the clusters are fewer than 4 per superfacet (an uneven
        surface): the caller runs on every element alone.
    info : dict
        ``coarse_elements``, ``coarse_passes``, ``coarse_iterations``, ``coarse_orphans``
        (the coarse run's centers seeded on clusters no center reached).

    ``on_coarsened()`` is called once the
    clusters are made, before the coarse run (the pipeline frees there what only
    the coarsening read).
    """

    co = coarsen(graph, csr_w, ratio)
    if on_coarsened is not None:
        on_coarsened()
    cg = co.graph
    if k is not None and cg.n_elements < _MIN_CLUSTERS * k:
        return None, dict(coarse_elements=cg.n_elements)  # too few clusters for k superfacets
    spaces = Workspaces(cg.n_elements, co.weights, n_threads)
    try:
        start = initial_centers(init, cg, co.weights, None if k is None else
                                min(k, cg.n_elements), radius, window, every_piece)
        work = np.empty(cg.n_elements, dtype=np.int64)
        work[:start.shape[0]] = start
        classifier = make_classifier(assignment, cg, co.weights, (window * radius) ** 2, spaces)
        it = passes.iterate(classifier, work, start.shape[0], np.ascontiguousarray(cg.sizes),
                     np.ascontiguousarray(cg.positions), max_iter, tol=tol, min_move=min_move)
    finally:
        spaces.close()
    n_lab = it.centers.shape[0]
    fine_label = it.label[co.cluster].astype(np.int32, copy=False)
    centers = update_centers(fine_label, n_lab, np.ascontiguousarray(graph.sizes),
                             np.ascontiguousarray(graph.positions),
                             np.full(n_lab, -1, dtype=np.int64))
    centers = centers[centers >= 0]
    info = dict(coarse_elements=cg.n_elements, coarse_passes=it.n_passes,
                coarse_iterations=it.n_iter, coarse_orphans=it.n_orphan_seeds)
    return centers, info


def coarsening_for(graph: ElementGraph, params, k: int | None, radius: float) -> int:
    """The coarsening of a run (an automatic rule): ``params.coarsen`` if given,
    else :func:`coarse_ratio` of the graph's kind when ``tol > 0`` (1 otherwise);
    capped at ``n / (8 k)`` (``k`` estimated from the radius when None: the area of
    a disc, or the volume of a ball on cells).

    Returns
    -------
    int
        Elements per cluster; 1: no coarse run.

    Examples
    --------
    >>> g = face_graph(as_mesh(trimesh.creation.icosphere(subdivisions=2)))
    >>> coarsening_for(g, resolve(n_segments=10), 10, 0.3)
    1
    """
    p = params
    if k is not None:
        k_est = k
    else:  # a disc's area on surfaces, a ball's volume on cells (paper section 3.1)
        dim = kind_of(graph.kind).dim
        each = math.pi * radius ** 2 if dim == 2 else superfacet_measure(radius, dim)
        k_est = max(1, round(graph.area / each))
    ratio = p.coarsen if p.coarsen is not None else (
        coarse_ratio(graph.n_elements, k_est, graph.kind, p.n_neighbors) if p.tol > 0 else 1)
    return max(1, min(ratio, graph.n_elements // (_MAX_RATIO_DIV * k_est)))


def start_centers(graph: ElementGraph, csr_w: np.ndarray, params,
                  k, radius: float, ratio: int, center_tol: float, timings: dict,
                  stage=lambda name: None, on_coarsened: Callable[[], None] | None = None):
    """The centers the passes on every element start from.

    Runs :func:`coarse_centers` with ``ratio`` elements per cluster
    (:func:`coarsening_for`), or the plain initialization when ``ratio`` is 1 or
    the coarse run finds too few clusters. Coarse-run details go to ``timings``
    (``coarse`` seconds, ``coarse_elements``, ``coarse_passes``). ``on_coarsened``
    as in :func:`coarse_centers`. Unless ``params.paper``, the
    farthest points seed every connected piece first
    (:func:`superfacets.method.initialization.farthest_point_centers`).

    Returns
    -------
    centers : (K,) int64 ndarray
    ratio : int
        The coarsening used (1: none).
    """
    import time

    p = params
    if ratio > 1:
        t = time.perf_counter()
        stage(f"coarse ({ratio}:1)")
        init, info = coarse_centers(
            graph, csr_w, ratio, init=p.init, k=k, radius=radius, window=p.window,
            assignment=p.assignment, max_iter=p.max_iter, tol=p.tol,
            min_move=center_tol * radius, n_threads=p.n_threads,
            every_piece=not p.paper, on_coarsened=on_coarsened)
        if init is not None:
            timings.update(info, coarse=time.perf_counter() - t)
            return init, ratio
    stage(f"init ({p.init})")
    return initial_centers(p.init, graph, weights_array(csr_w), k, radius, p.window,
                           not p.paper), 1
