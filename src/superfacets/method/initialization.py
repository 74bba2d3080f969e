"""Initializations of the iteration (paper section 3.1; ``docs/notes/method.md``, section 3).

- :func:`farthest_point_centers`: ``k`` center elements, given the number of
  superfacets;
- :func:`flood_labels` and :func:`grid_labels`: initial regions, given the
  radius ``r`` (absolute units here; the public API takes it as a fraction
  of the bounding-box diagonal);
- :func:`initial_centers`: the centers of any of them, by name.

Each takes an element graph (or a mesh, for its face graph).
"""

from __future__ import annotations

import numpy as np

from .._kernels import native
from ..elements.builders import as_element_graph
from ..inputs.bounds import nearest_row
from .expansion import Workspace, bucket_width, with_room
from .params import DEFAULTS, INITS, check_choice, check_n_segments
from .passes import update_centers

__all__ = ["first_center", "piece_seeds", "farthest_point_centers", "flood_labels",
           "grid_labels", "initial_centers", "INITS"]

_BLOCKED_MIN_WORK = 300_000  # elements x centers above which the cells pay (about 0.5 ms there)


def first_center(graph) -> int:
    """The element whose position is closest to the input's centroid.

    For a mesh, the centroid is the mean of the referenced vertex positions,
    as in the authors' implementation (unreferenced vertices are ignored).
    Ties go to the lowest index.

    Parameters
    ----------
    graph : ElementGraph, Mesh, trimesh.Trimesh or (vertices, faces)

    Returns
    -------
    int
        An element index.
    """
    g = as_element_graph(graph)
    return nearest_row(g.positions, g.centroid)


def _pieces(g) -> tuple[np.ndarray, int]:
    """Connected piece of every element (numbered by lowest element) and their number."""
    same_label_components = native.kernel("connectivity.same_label_components")

    n = g.n_elements
    piece = same_label_components(g.indptr, g.indices, np.zeros(n, dtype=np.int64))
    return piece, (int(piece.max()) + 1 if n else 0)


def piece_seeds(graph, pieces: tuple[np.ndarray, int] | None = None) -> np.ndarray:
    """One seed in every connected piece of the element graph.

    The first is :func:`first_center` (the paper's first center); then, for
    every other piece in the order of its lowest element, the element of that
    piece nearest the mean position of its elements (ties: the lowest index).
    O(n + e).

    Parameters
    ----------
    graph : ElementGraph, Mesh, trimesh.Trimesh or (vertices, faces)
    pieces : (piece, n_pieces), optional
        The graph's connected pieces, if known.

    Returns
    -------
    seeds : (P,) int64 ndarray
        ``P`` the number of pieces (1 for a connected graph: ``[first_center]``).

    Examples
    --------
    >>> a, b = trimesh.creation.icosphere(1), trimesh.creation.icosphere(1)
    >>> both = np.r_[a.vertices, b.vertices + 5], np.r_[a.faces, b.faces + len(a.vertices)]
    >>> len(piece_seeds(both))
    2
    """
    g = as_element_graph(graph)
    first = first_center(g)
    piece, n_pieces = pieces if pieces is not None else _pieces(g)
    if n_pieces <= 1:
        return np.array([first], dtype=np.int64)
    pos = np.asarray(g.positions, dtype=np.float64)
    count = np.bincount(piece, minlength=n_pieces).astype(np.float64)
    mean = np.stack([np.bincount(piece, weights=pos[:, t], minlength=n_pieces)
                     for t in range(3)], axis=1) / count[:, None]
    d2 = ((pos - mean[piece]) ** 2).sum(axis=1)
    nearest = _nearest_per_piece(piece, d2, n_pieces)
    return np.r_[first, np.delete(nearest, piece[first])].astype(np.int64)


def _nearest_per_piece(piece: np.ndarray, d2: np.ndarray, n_pieces: int) -> np.ndarray:
    """Each piece's element of least ``d2`` (ties: the lowest index), in two passes, not
    a sort of every element by piece and distance (10M points in 100,000 pieces: 4.3 ->
    0.07 s; the same elements)."""
    best = np.full(n_pieces, np.inf)
    np.minimum.at(best, piece, d2)
    at = np.flatnonzero(d2 == best[piece])  # (each piece's least, ties included)
    _, first = np.unique(piece[at], return_index=True)  # (the first of each: lowest)
    return at[first]


def farthest_point_centers(graph, n_segments: int, *, every_piece: bool = False) -> np.ndarray:
    """Iterative farthest-point initialization (paper section 3.1).

    The first center is :func:`first_center`; each next one is the element
    whose position has the largest Euclidean distance to its nearest chosen
    center (with ``graph.scale2``, a content-sensitive run of
    :mod:`superfacets.elements.density`, that distance times ``sqrt(scale2)`` of the
    element: centers closer together where it is large). With ``every_piece``
    (beyond the paper), every connected piece
    of the graph gets a center within the ``k``: the paper's first ``L``
    centers, ``L`` the largest for which they and one seed
    (:func:`piece_seeds`) in each piece they missed make at most ``k``, then
    those seeds. A piece the farthest points missed would otherwise seed a
    superfacet from its orphans during the passes, beyond the count asked
    for. A graph of more pieces than ``n_segments`` gets one center per
    piece. Runs in O(n k) time at worst and O(n) memory (a running minimum),
    instead of the paper's O(n k^2); in practice close to O(n log k): the
    elements are grouped in grid cells, and a new center visits only the
    cells where it can be nearer than the earlier centers (exactly the same
    centers, ties included, as the plain O(n k) loop; tested).

    Parameters
    ----------
    graph : ElementGraph, Mesh, trimesh.Trimesh or (vertices, faces)
    n_segments : int
        Number of centers ``k``, ``1 <= k <= n``.
    every_piece : bool, default False
        Give every connected piece a center (the paper: False).

    Returns
    -------
    centers : (K,) int64 ndarray
        Distinct element indices, in the order they were chosen; ``K = k``,
        or the number of pieces if ``every_piece`` and that is larger.

    Raises
    ------
    ParameterError
        If ``n_segments`` is not in ``1..n``.

    Examples
    --------
    >>> ico = trimesh.creation.icosphere(subdivisions=2)
    >>> farthest_point_centers((ico.vertices, ico.faces), 4).shape
    (4,)
    """
    g = as_element_graph(graph)
    k = check_n_segments(n_segments, g.n_elements, g.kind)
    out = _farthest_run(g, k)
    piece, n_pieces = _kept_pieces(g)[:2] if every_piece else (None, 1)
    if n_pieces <= 1:
        return out
    # the longest run of farthest points that, with one seed in each piece it
    # missed, makes at most k centers (the samples are incremental: a prefix of
    # the k is the run for fewer); the centers in all after t + 1 of them:
    new_piece = np.zeros(k, dtype=np.int64)
    new_piece[np.unique(piece[out], return_index=True)[1]] = 1
    used = np.arange(1, k + 1) + n_pieces - np.cumsum(new_piece)  # non-decreasing
    keep = max(1, int(np.searchsorted(used, k, side="right")))
    seeds = _kept_pieces(g)[2]
    missed = np.ones(n_pieces, dtype=bool)
    missed[piece[out[:keep]]] = False
    return np.r_[out[:keep], seeds[missed[piece[seeds]]]].astype(np.int64)


def _kept_pieces(g) -> tuple:
    """The connected pieces of graph ``g`` (:func:`_pieces`) and their seeds
    (:func:`piece_seeds`), found once and kept with it (a tile samples twice)."""
    kept = g.__dict__.get("_piece_seeds")
    if kept is None:
        piece, n_pieces = _pieces(g)
        seeds = piece_seeds(g, (piece, n_pieces)) if n_pieces > 1 else None
        kept = g.__dict__["_piece_seeds"] = (piece, n_pieces, seeds)
    return kept


def _farthest_run(g, k: int) -> np.ndarray:
    """The first ``k`` farthest points of graph ``g`` (a new array). The sampling is
    incremental (the first ``k`` of a longer run are the run for ``k``), so the longest
    run asked of a graph is kept with it and a shorter one read from it: a tiled run's
    tile samples once to find its core's share and starts from a prefix of the same run
    (10M points in 16 tiles: 4.7 of the centers phase's 15 s)."""
    scale2 = g.scale2  # content-sensitive runs (superfacets.elements.density); None: the paper's
    kept = g.__dict__.get("_farthest_run")
    if kept is not None and kept[0] is scale2 and kept[1].size >= k:
        return kept[1][:k].copy()
    out = np.empty(k, dtype=np.int64)
    c = np.ascontiguousarray(g.positions)
    m = c.shape[0]
    if m * k < _BLOCKED_MIN_WORK:
        native.kernel("farthest.farthest_point")(c, k, first_center(g), out, scale2)
    else:  # same result; each new center visits only the grid cells it can change
        cells = max(2, round(m ** (1 / 3)))  # cells^3 ~ m: the count array stays O(m)
        order, bstart, bcenter, bradius = native.kernel("farthest.spatial_blocks")(c, cells)
        farthest_point_blocked = native.kernel("farthest.farthest_point_blocked")
        if scale2 is None:
            farthest_point_blocked(c, k, first_center(g), out, order, bstart, bcenter, bradius)
        else:
            s2 = np.ascontiguousarray(scale2[order])
            farthest_point_blocked(c, k, first_center(g), out, order, bstart, bcenter, bradius,
                                   s2, np.minimum.reduceat(s2, bstart[:-1]))  # (a bound)
    g.__dict__["_farthest_run"] = (scale2, out.copy())  # (kept read-only: a copy is returned)
    return out


def flood_labels(graph, csr_weights: np.ndarray, radius: float,
                 window: float = DEFAULTS.window) -> np.ndarray:
    """Flood initialization (paper section 3.1; authors' implementation).

    Elements are ordered by Euclidean distance to the first seed,
    :func:`first_center`. The nearest element not yet labelled starts a new
    region, grown over the graph by a bounded expansion that claims only
    unlabelled elements within ``window * radius`` (Euclidean) of the seed —
    the paper's "a face farther than 2r from the seed starts a new region"
    with the default ``window = 2``. Repeats until every element has a label.

    Parameters
    ----------
    graph : ElementGraph, Mesh, trimesh.Trimesh or (vertices, faces)
    csr_weights : (2 e,) float64 ndarray
        Weight of each CSR entry of the graph.
    radius : float
        Superfacet radius ``r`` in mesh units, ``> 0``.
    window : float, default 2
        Expansion multiple.

    Returns
    -------
    labels : (n,) int64 ndarray
        Region of each element, dense ``0..R-1`` in order of creation.
    """
    g = as_element_graph(graph)
    c = np.ascontiguousarray(g.positions)
    seed = first_center(g)
    order = np.argsort(((c - c[seed]) ** 2).sum(axis=1), kind="stable").astype(np.int64)
    m = g.n_elements
    labels = np.empty(m, dtype=np.int64)
    inv_width, n_buckets = bucket_width(csr_weights)
    ws = Workspace(m, n_buckets, g.indices.shape[0] + m + 1)
    flood = native.kernel("expand.flood")
    with_room(ws, lambda ws: flood(g.indptr, g.indices, csr_weights, c, order,
                                   float((window * radius) ** 2), labels, ws.local,
                                   ws.queue, inv_width, ws.vis))
    return labels


def grid_labels(graph, radius: float) -> np.ndarray:
    """Regular-grid initialization (paper section 3.1).

    Each element position is integer-divided by ``2 r`` after subtracting the
    minimum corner of the input's bounding box, so the grid moves with the
    input (translation invariance); elements in the same cell of the 3D grid
    start in the same region. Cells are numbered in lexicographic order of
    their integer coordinates. O(n log n) (a sort stands in for a hash map).

    Parameters
    ----------
    graph : ElementGraph, Mesh, trimesh.Trimesh or (vertices, faces)
    radius : float
        Superfacet radius ``r`` in mesh units, ``> 0``.

    Returns
    -------
    labels : (n,) int64 ndarray
        Region of each element, dense ``0..R-1``.
    """
    g = as_element_graph(graph)
    cell = np.floor((g.positions - g.lower) / (2.0 * radius)).astype(np.int64)
    dims = cell.max(axis=0) + 1
    key = (cell[:, 0] * dims[1] + cell[:, 1]) * dims[2] + cell[:, 2]
    _, labels = np.unique(key, return_inverse=True)
    return labels.astype(np.int64).ravel()


def initial_centers(init: str, graph, csr_weights: np.ndarray, k: int | None, radius: float,
                    window: float, every_piece: bool = False) -> np.ndarray:
    """The initial centers of ``init``: ``k`` farthest points, or the element
    nearest the area-weighted mean of each flood or grid region.

    Parameters
    ----------
    init : {'farthest', 'flood', 'grid'}
    graph : ElementGraph
    csr_weights : (2 e,) float64 ndarray
    k : int or None
        Number of centers (``'farthest'``).
    radius : float
        Superfacet radius in mesh units (``'flood'``, ``'grid'``).
    window : float
        Expansion multiple (``'flood'``).
    every_piece : bool, default False
        ``'farthest'``: give every connected piece a center within ``k``
        (:func:`farthest_point_centers`).

    Returns
    -------
    centers : (K,) int64 ndarray

    Raises
    ------
    ParameterError
        On an unknown ``init``.
    """
    check_choice("init", init, INITS)
    if init == "farthest":
        return farthest_point_centers(graph, k, every_piece=every_piece)
    labels = (flood_labels(graph, csr_weights, radius, window) if init == "flood"
              else grid_labels(graph, radius))
    n = int(labels.max()) + 1
    return update_centers(labels.astype(np.int32), n, np.ascontiguousarray(graph.sizes),
                          np.ascontiguousarray(graph.positions), np.full(n, -1, dtype=np.int64))
