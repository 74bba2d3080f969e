"""Stage 9 where ``merge_from > 1`` (the default on clouds of even density): many
superpoints, merged down to the count asked for, flat neighbours first.

The run segments ``merge_from`` times the ``k`` asked for (:func:`superfacets.method.stages.
resolve_rules`), then :func:`merge_to_count` merges adjacent superpoints in two phases:

1. **Flat merges** (:func:`flat_merges`): two neighbours may merge when the squared
   distances of their union to its least-squares plane
   (:func:`superfacets.graph.hierarchy.planarity_graph`: each point weighs one) rise by
   at most :data:`FLAT_NOISE` times the input's noise (:func:`noise_variance`) per
   point of the smaller one (of at least :data:`FLAT_MIN_ELEMENTS`: a piece of a few
   points is not failed by its noise alone), plus float64's rounding of the union's plane
   fit (:data:`PLANE_ROUNDING` times its scatter's trace: an exact plane's pieces merge):
   its points lie on the larger's plane, to within the scanner's noise. Among those
   pairs the cheapest by Ward's cost merges first, so a flat region grows in compact
   pieces. Walls, floors, ground and the flat faces of
   objects become large superpoints; curved surfaces, whose planes bend beyond the
   noise, keep theirs.
2. Down to ``k`` (or the input's separate pieces, where there are more), by one of two
   costs, chosen by what phase 1 found (:func:`flat_share`):

   - where most of the elements (:data:`FLAT_SHARE`) lie in flat regions (a scene:
     floors, walls, ground, the flat faces of machined parts), the **plane's rise**
     (:func:`merge_nodes`): the pair whose union leaves its plane least merges first,
     so the count goes to what stands on the flat regions, not to the regions (with
     colours, neighbours of one colour first: a rug is as flat as its floor);
   - elsewhere (an object of curved parts), **Ward's merges** with the run's crease
     factor (:func:`superfacets.method.finish.exact_count`): compact superpoints,
     merged along the creases.

With ``merge_cost='scene'`` phase 2 is one cost on every input instead
(:func:`scene_merge_nodes`): the plane's rise in units of the scan's noise or of the
neighbourhoods' own plane residual (:func:`ring_residual`, the larger), plus Ward's term in
units of the superpoint's size, times the crease factor. It keeps more class borders on
scans of scenes and noisy objects, and fewer parts on noise-free sampled surfaces
(``docs/notes/superpoints-defaults.md``, "The merges' cost scaled by the parts' own
residual"). With ``merge_cost='noise'`` the rise of that cost is weighted by the noise's
share of the first superpoints' residual (:func:`rise_weight`); on an input whose noise
reads 0 (a noise-free sampled surface) its merges are the default's.

Neither the flat merges nor the plane's rise make a superpoint of more than
``max_size_ratio`` times the mean count (the elements over ``k``; 16 by default, 4 on a
scene) while another pair may merge: a coplanar pair costs them nothing whatever its size, and flat
ground grown without bound lost the class borders inside it (low vegetation on the
ground). So the count a room spends on its walls goes to the objects on them, and an
object of no flat face gets the method's compact superpoints, merged from finer ones
along its creases. Not in the paper: graph partitions of scans (the ScanNet Segmentator,
cut pursuit) leave flat regions whole the same way. What they gain and lose, measured:
``docs/notes/superpoints-defaults.md``.
"""

from __future__ import annotations

import math

import numpy as np

from .._kernels import native
from .._runtime.arrays import real_rows
from ..elements.labels import check_labels
from ..graph import hierarchy
from ..graph.hierarchy import merge_arrays, pieces
from ..graph.sums import border_sums, grouped_graph, grouped_planes, point_sums

__all__ = ["merge_to_count", "merge_nodes", "flat_merges", "flat_share", "flat_merge_nodes",
           "rise_merge_nodes", "scene_merge_nodes", "ring_residual", "rise_weight",
           "same_feature_edges", "feature_spread", "noise_variance", "neighbourhood_noise",
           "noise_of", "NOISE_SIGNIFICANCE", "FLAT_NOISE", "FLAT_MIN_ELEMENTS", "FLAT_SHARE",
           "NOISE_SAMPLE", "PLANE_ROUNDING"]

#: A flat merge's largest rise of the squared plane distances, per element of the
#: smaller superpoint, in units of :func:`noise_variance` (chosen among 1, 2 and 3:
#: ``docs/notes/superpoints-defaults.md``).
FLAT_NOISE = 2.0
#: The fewest elements a flat merge's rise is read over (per element of the smaller
#: superpoint, :data:`FLAT_NOISE`): below about 12 one point's noise decides the test.
#: Under noise alone a union's rise is the noise times a chi-squared of at most three
#: degrees of freedom (the planes' parameters), whatever the sizes; read over 12
#: elements a flat pair fails the test with a chance of about 1 in 300 (three sigma),
#: over 1 to 5 with a chance of 10-30 %, which left pieces of 1-11 points on level
#: ground as superpoints of their own (``docs/notes/superpoints.md``). 0: each piece's
#: own count, before 2026-12-02. The first run's superpoints hold as many on average
#: (:data:`superfacets.method.rules.MIN_FINE_ELEMENTS`).
FLAT_MIN_ELEMENTS = 12.0
#: The share of the elements in flat regions (superpoints the flat merges grew from two
#: or more) from which phase 2 merges by the plane's rise, not by Ward's cost: most of
#: them, on every input, scan or sampled surface (the measurements behind it:
#: ``docs/notes/superpoints-defaults.md``).
FLAT_SHARE = 0.5
#: The most elements :func:`noise_variance` reads (evenly spaced in the input's order).
NOISE_SAMPLE = 8_192
#: A neighbourhood's smallest eigenvalue at most this times its largest is 0 in
#: :func:`neighbourhood_noise`: float64's rounding of the covariance (64 machine epsilons),
#: not noise; and, times a union's scatter's trace, the rise the flat merges allow beyond
#: the noise (the compiled merging's ``ROUNDING``).
PLANE_ROUNDING = 64 * float(np.finfo(np.float64).eps)


def noise_variance(graph) -> float:
    """The input's noise: the median over elements of the noise of the surface around
    each (:func:`neighbourhood_noise`: the smallest eigenvalue of the neighbourhood's
    covariance, read at two scales, the curvature's share taken out), in squared input
    units.

    On a scan, the squared distance of the points to a plane where the surface is
    flat: the scanner's noise; on a clean sampled surface about 0, however curved (a
    single scale read the curvature over one neighbourhood as noise, and let the flat
    merges cross the parts of pliers and glasses). Read on at most
    :data:`NOISE_SAMPLE` elements, evenly spaced.

    Parameters
    ----------
    graph : ElementGraph
        With ``positions`` and the CSR adjacency (``indptr``, ``indices``).

    Returns
    -------
    float
        ``>= 0``.

    Raises
    ------
    ParameterError
        Never: nothing is checked beyond the graph.

    Examples
    --------
    >>> rng = np.random.default_rng(0)
    >>> xy = rng.random((4000, 2))
    >>> g = point_graph(PointCloud(np.c_[xy, 0.001 * rng.standard_normal(4000)])).graph
    >>> 0.3e-6 < noise_variance(g) < 1e-6      # the plane's noise: 0.001 squared, less a bit
    True
    """
    n = graph.n_elements
    pick = np.unique(np.linspace(0, n - 1, min(n, NOISE_SAMPLE)).astype(np.int64))
    return noise_of(neighbourhood_noise(graph, pick)) if n else 0.0


#: How many standard errors above 0 the median of the neighbourhoods' noise must lie, by
#: the sign test, to read as noise (:func:`noise_of`): 3, a conventional level.
NOISE_SIGNIFICANCE = 3.0


def noise_of(estimates: np.ndarray) -> float:
    """The input's noise from the neighbourhoods' estimates (:func:`neighbourhood_noise`):
    their median, where it lies significantly above 0, else 0.

    On a noise-free surface the estimates scatter about 0 (the curvature taken out
    leaves a small error either way), and their median is a tiny number of either
    sign: read as it is, two samples of the same surface (one run's and a tiled run's)
    could read 0 and a tiny noise, and merge by different rules. So the median is the
    noise only where the sign test puts it above 0 at :data:`NOISE_SIGNIFICANCE`
    standard errors: the estimate of rank ``floor(m / 2 - z sqrt(m) / 2)`` (of ``m``
    in increasing order, the median's lower confidence bound, free of any
    distribution) is positive. A scan's estimates are nearly all positive.

    Parameters
    ----------
    estimates : (m,) float ndarray
        Squared input units; any sign.

    Returns
    -------
    float
        ``>= 0``: the median of ``estimates``, or 0 (also for fewer than 9 estimates,
        where no median is significant at 3 standard errors).

    Raises
    ------
    ParameterError
        Never.

    Examples
    --------
    >>> rng = np.random.default_rng(0)
    >>> scatter = 1e-12 * rng.standard_normal(8000)         # a clean curved surface
    >>> noise_of(scatter), noise_of(np.abs(scatter)) > 0
    (0.0, True)
    >>> noise_of(np.array([-1.0, 4.0, 4.0])), noise_of(np.full(9, 4.0))
    (0.0, 4.0)
    """
    e = np.sort(np.asarray(estimates, dtype=np.float64).ravel())
    m = e.size
    rank = math.floor(m / 2 - NOISE_SIGNIFICANCE * math.sqrt(m) / 2)
    if m == 0 or rank < 0 or not e[rank] > 0:
        return 0.0
    return float(np.median(e))


def neighbourhood_noise(graph, pick: np.ndarray) -> np.ndarray:
    """The noise of the surface around each element ``pick`` (int64, distinct), what
    :func:`noise_variance` takes the median of ((len(pick),) float64, squared input
    units; a tiled run gathers them from every tile).

    The smallest eigenvalue of a neighbourhood's covariance is the noise plus what the
    curvature leaves over its extent, which grows as the fourth power of its radius. So
    it is read at two scales, ``l1`` on the element and its graph neighbours (radius
    ``r1``, their mean distance to it) and ``l2`` on those and their neighbours (``r2``),
    and the curvature's share taken out: ``(q l1 - l2) / (q - 1)``, ``q = (r2 / r1)^4``
    (an estimate at radius 0). On a scan's flat parts ``l1`` and ``l2`` are both the
    noise; on a clean sampled surface, curved everywhere, the estimate is about 0. An
    eigenvalue within the rounding of its covariance (:data:`PLANE_ROUNDING` times the
    largest) is 0: a neighbourhood on an exact plane (a machined part's face, sampled)
    has no noise, whatever the rounding left in float64.
    """
    l1, r1 = _plane_residual(graph, pick, 1)
    l2, r2 = _plane_residual(graph, pick, 2)
    q = (r2 / np.where(r1 > 0, r1, 1.0)) ** 4
    ok = (r1 > 0) & (q > 1.0 + 1e-9)
    return np.where(ok, (q * l1 - l2) / np.where(ok, q - 1.0, 1.0), l1)


def _plane_residual(graph, pick: np.ndarray, rings: int) -> tuple[np.ndarray, np.ndarray]:
    """Per element of ``pick``: the smallest eigenvalue of the covariance of the elements
    within ``rings`` graph steps of it (itself included), and their mean distance to it
    (compiled passes on threads: ``normals.neighbourhood_moments``, then
    ``normals.extreme_eigenvalues``, Jacobi's rotations)."""
    pick = np.ascontiguousarray(pick, dtype=np.int64)
    cov, radius = np.empty((pick.size, 3, 3)), np.empty(pick.size)
    native.kernel("normals.neighbourhood_moments")(
        np.ascontiguousarray(graph.indptr, dtype=np.int64), np.ascontiguousarray(graph.indices),
        np.ascontiguousarray(graph.positions, dtype=np.float64), pick, int(rings), cov, radius)
    low, high = np.empty(pick.size), np.empty(pick.size)
    native.kernel("normals.extreme_eigenvalues")(cov, low, high)
    return np.where(low > PLANE_ROUNDING * high, low, 0.0), radius


def flat_merges(graph, labels: np.ndarray, k: int, max_rise: float, *,
                alpha: float = 0.0, eta_convex: float = 0.0,
                features: np.ndarray | None = None, max_jump: float = 0.0) -> np.ndarray:
    """Phase 1 of :func:`merge_to_count`: merge adjacent superpoints whose union stays
    flat, the cheapest by Ward's cost first, while more than ``k`` remain.

    A pair may merge when the squared distances of its union to their best plane
    (:func:`superfacets.graph.hierarchy.planarity_graph`: each point weighs one) rise
    by at most ``max_rise`` per element of the smaller superpoint (of at least
    :data:`FLAT_MIN_ELEMENTS`: a piece of a few points fails by its noise); among those, the
    pair of least Ward's cost with the crease factor merges first
    (:func:`superfacets.graph.hierarchy.hierarchy`), so that a flat region grows into
    compact pieces where it must stop at ``k``. Merging stops once no pair may merge
    or ``k`` superpoints remain.

    Parameters
    ----------
    graph : ElementGraph
    labels : (n,) int64 ndarray
        Dense superpoint labels ``0..K-1``, each superpoint connected.
    k : int
        The fewest superpoints to leave (``>= 1``).
    max_rise : float
        In squared input units (``FLAT_NOISE * noise_variance(graph)``).
    alpha, eta_convex : float, default 0
        The crease factor of Ward's cost (paper eqs. 2-3), ``>= 0``.
    features : (n, d) float ndarray, optional
        With them, only neighbours whose mean features differ by at most ``max_jump``
        may merge (a run's colour term: a board on a wall is flat too).
    max_jump : float, default 0
        ``>= 0`` (a run's feature floor: the colours' noise between neighbouring points).

    Returns
    -------
    (n,) int64 ndarray
        Dense labels, numbered by their lowest superpoint.

    Raises
    ------
    ParameterError
        If the labels do not fit the graph.

    Examples
    --------
    >>> x = np.linspace(0, 1, 40)
    >>> xy = np.stack(np.meshgrid(x, x), -1).reshape(-1, 2)
    >>> roof = np.c_[xy, np.abs(xy[:, 0] - 0.5)]             # two planes meeting at a ridge
    >>> g = point_graph(PointCloud(roof)).graph
    >>> cells = (g.positions[:, 0] * 7.999).astype(np.int64) * 8 + \\
    ...     (g.positions[:, 1] * 7.999).astype(np.int64)     # 8 x 8 squares
    >>> merged = flat_merges(g, cells, 1, 1e-9)
    >>> int(merged.max()) + 1                              # one per plane
    2
    """
    lab, nodes, pairs = _sums(graph, labels, features)
    unit = _planes_graph(nodes, pairs, None, None if features is None else max_jump)
    return flat_merge_nodes(unit, k, max_rise, alpha, eta_convex, 0.0, FLAT_MIN_ELEMENTS)[lab]


def feature_spread(labels: np.ndarray, features: np.ndarray, k: int, *, sums=None
                   ) -> np.ndarray:
    """The spread of each superpoint's features: the variance about their mean, summed
    over the features ((k,) float64, ``>= 0``), from the elements' ``labels`` (dense,
    ``0..k-1``) and ``features`` ((n, d)); or from ``sums`` = ``(count (k,), sum (k, d),
    sum of squares (k, d))`` (a tiled run's, summed over its tiles).

    Examples
    --------
    >>> f = np.array([[0.0], [1.0], [0.5], [0.5]])
    >>> feature_spread(np.array([0, 0, 1, 1]), f, 2).tolist()
    [0.25, 0.0]
    """
    if sums is None:
        count = np.bincount(labels, minlength=k).astype(np.float64)
        cols = range(features.shape[1])
        total = np.stack([np.bincount(labels, weights=features[:, c], minlength=k)
                          for c in cols], 1)
        squares = np.stack([np.bincount(labels, weights=features[:, c] ** 2, minlength=k)
                            for c in cols], 1)
    else:
        count, total, squares = sums
    n = np.maximum(count, 1.0)[:, None]
    mean = total / n
    return np.maximum(squares / n - mean * mean, 0.0).sum(axis=1)


def same_feature_edges(pg, max_jump: float, spread: np.ndarray | None = None, *,
                       free_below: float = 0.0):
    """``pg`` with only its edges between superpoints whose mean features differ by at
    most ``max_jump``, or by at most their features' spread within them
    (``sqrt(spread_a + spread_b)``, :func:`feature_spread`, where given): a textured
    surface (grass, a photograph's shadows) keeps neighbours whose means differ by less
    than the texture, a board whose colour is even stays apart from its wall. With
    ``free_below``, an edge one of whose superpoints has a smaller ``area`` is kept
    whatever the colours (a few points of another colour are noise, not a board). The
    result has ``feature`` None again: the merges order by geometry.

    Examples
    --------
    >>> from superfacets.graph.hierarchy import planarity_graph
    >>> g = point_graph(PointCloud(np.c_[np.random.default_rng(0).random((600, 2)),
    ...                                   np.zeros(600)])).graph
    >>> third = (g.positions[:, 0] * 2.999).astype(np.int64)       # three strips
    >>> colour = (third == 2).astype(float)[:, None]                 # the last one another
    >>> pg = planarity_graph(g, third, colour)
    >>> same_feature_edges(pg, 0.1).edge_index.T.tolist()
    [[0, 1]]
    """
    from dataclasses import replace

    a, b = np.asarray(pg.edge_index, dtype=np.int64)
    jump = np.linalg.norm(pg.feature[a] - pg.feature[b], axis=1)
    limit = max(float(max_jump), 1e-9)
    if spread is not None:
        limit = np.maximum(limit, np.sqrt(spread[a] + spread[b]))
    keep = (jump <= limit) | (np.minimum(pg.area[a], pg.area[b]) < free_below)
    return replace(pg, edge_index=pg.edge_index[:, keep], border_length=pg.border_length[keep],
                   mean_angle=pg.mean_angle[keep], concave=pg.concave[keep], feature=None)


def flat_merge_nodes(pg, k: int, max_rise: float, alpha: float = 0.0,
                     eta_convex: float = 0.0, max_size: float = 0.0,
                     min_count: float = FLAT_MIN_ELEMENTS) -> np.ndarray:
    """:func:`flat_merges` on a superpoint graph whose ``area``, ``centroid`` and
    ``scatter`` are the points' count, mean and scatter
    (:func:`superfacets.graph.hierarchy.planarity_graph`): the merged superpoint of
    each node ((K,) int64, dense, numbered by their lowest node); with ``max_size > 0``,
    no merge makes a superpoint of more elements; a pair's rise read over at least
    ``min_count`` elements (:data:`FLAT_MIN_ELEMENTS`)."""
    return _merged(pg, 2, k, float(alpha), float(eta_convex), float(max_rise), max_size,
                   min_count=float(min_count))


def rise_merge_nodes(pg, k: int, max_size: float = 0.0) -> np.ndarray:
    """The plane's rise on a superpoint graph as :func:`flat_merge_nodes` reads it: the
    pair whose union leaves its least-squares plane least merges first, until ``k``
    nodes remain or, with ``max_size > 0``, no pair can merge without making a
    superpoint of more elements (the count then not reached). Each node's group ((K,)
    int64, dense, numbered by their lowest node)."""
    return _merged(pg, 1, k, 0.0, 0.0, np.inf, max_size)


def scene_merge_nodes(pg, k: int, unit: float, size: float, alpha: float,
                      eta_convex: float, max_size: float = 0.0) -> np.ndarray:
    """The scene's cost on a superpoint graph as :func:`flat_merge_nodes` reads it: the pair
    of least ``(rise / unit + ward / size) * (1 + alpha s / pi)`` merges first, the rise of
    the squared distances to the union's least-squares plane in units of ``unit``, Ward's
    term (the rise of the points' spread about their mean) in units of ``size`` and the
    paper's crease factor (eqs. 2-3), until ``k`` nodes remain or, with ``max_size > 0``, no
    pair can merge without making a superpoint of more elements.

    Parameters
    ----------
    pg : SuperfacetGraph
        Its ``area`` the points' counts, ``centroid`` their means, ``scatter`` theirs.
    k : int
    unit, size : float
        Squared input units, ``> 0``: the rise's (a plane residual per point) and Ward's
        (a superpoint's area over pi).
    alpha, eta_convex : float
        The crease factor's.
    max_size : float, default 0

    Returns
    -------
    (K,) int64 ndarray
        Each node's group, dense, numbered by their lowest node.

    Raises
    ------
    ParameterError
        Never on a graph of valid sums.

    Examples
    --------
    >>> from superfacets.graph.adjacency import SuperfacetGraph
    >>> pg = SuperfacetGraph(edge_index=np.array([[0, 1], [1, 2]]), border_length=np.ones(2),
    ...                      mean_angle=np.zeros(2), concave=np.zeros(2), area=np.ones(3),
    ...                      centroid=np.array([[0.0, 0, 0], [1, 0, 0], [3, 0, 0]]),
    ...                      normal=np.zeros((3, 3)), feature=None, scatter=np.zeros((3, 3, 3)))
    >>> scene_merge_nodes(pg, 2, 1.0, 1.0, 0.0, 0.0).tolist()   # the nearer pair first
    [0, 0, 1]
    """
    return _merged(pg, 3, k, float(alpha), float(eta_convex), float(unit), max_size,
                   1.0 / float(size))


def ring_residual(pg) -> float:
    """The median plane residual per point of each node's union with its neighbours (about
    ``merge_from`` first superpoints: the superpoints asked for), squared input units: the
    scene's cost's unit of the rise where it is above the scan's noise.

    Parameters
    ----------
    pg : SuperfacetGraph
        As :func:`scene_merge_nodes` reads it.

    Returns
    -------
    float
        ``>= 0``; 0 for an empty graph.

    Raises
    ------
    ParameterError
        Never.

    Examples
    --------
    >>> from superfacets.graph.adjacency import SuperfacetGraph
    >>> corners = np.array([[1.0, 1, 1], [1, -1, -1], [-1, 1, -1], [-1, -1, 1]])
    >>> pg = SuperfacetGraph(edge_index=np.array([[0, 0, 0, 1, 1, 2], [1, 2, 3, 2, 3, 3]]),
    ...                      border_length=np.ones(6), mean_angle=np.zeros(6),
    ...                      concave=np.zeros(6), area=np.ones(4), centroid=corners,
    ...                      normal=np.zeros((4, 3)), feature=None, scatter=np.zeros((4, 3, 3)))
    >>> round(ring_residual(pg), 12)   # every ring: a tetrahedron's corners (scatter 4 I)
    1.0
    """
    k = int(pg.n_segments)
    if k == 0:
        return 0.0
    count = np.asarray(pg.area, dtype=np.float64)
    mean = np.asarray(pg.centroid, dtype=np.float64)
    ea, eb = np.asarray(pg.edge_index, dtype=np.int64).reshape(2, -1)
    keep = ea != eb
    own = np.arange(k, dtype=np.int64)
    # (owner, member) pairs as one key each, sorted: each sum below adds in that order
    ring = np.unique(np.r_[own * k + own, ea[keep] * k + eb[keep], eb[keep] * k + ea[keep]])
    owner, member = ring // k, ring % k
    weight = count[member]
    n = np.bincount(owner, weights=weight, minlength=k)
    centre = np.stack([np.bincount(owner, weights=weight * mean[member, c], minlength=k)
                       for c in range(3)], 1)
    centre /= np.maximum(n, 1e-300)[:, None]
    d = mean[member] - centre[owner]
    part = (np.asarray(pg.scatter, dtype=np.float64)[member]
            + weight[:, None, None] * d[:, :, None] * d[:, None, :]).reshape(-1, 9)
    union = np.stack([np.bincount(owner, weights=part[:, j], minlength=k) for j in range(9)],
                     1).reshape(k, 3, 3)
    residual = np.maximum(np.linalg.eigvalsh(union)[:, 0], 0.0) / np.maximum(n, 1e-300)
    return float(np.median(residual))


def rise_weight(noise: float, count: np.ndarray, scatter: np.ndarray) -> float:
    """The weight of the plane's rise in ``merge_cost='noise'``: ``min(1, s / v)``, the
    scan's noise ``s`` over the superpoints' median plane residual per point ``v``, both
    variances: the noise's share of what the superpoints hold. 1 where the noise is all
    they hold (flat ground, walls), small where they are much rougher than the noise
    (vegetation, an object's fine detail), 0 where the noise reads 0 (where
    :func:`merge_nodes` then keeps today's rule).

    Parameters
    ----------
    noise : float
        The scan's noise variance (:func:`noise_variance`), squared input units, ``>= 0``.
    count : (K,) float ndarray
        Points per superpoint (the first superpoints, before any merge).
    scatter : (K, 3, 3) float ndarray
        Their scatter about their means.

    Returns
    -------
    float
        In ``[0, 1]``; 1 for no superpoints or none with a residual, where the noise is
        positive.

    Raises
    ------
    ParameterError
        Never.

    Examples
    --------
    >>> rough = np.tile(4.0 * np.eye(3), (2, 1, 1))   # residual 4 over 4 points: 1.0 each
    >>> rise_weight(0.25, np.full(2, 4.0), rough), rise_weight(0.0, np.full(2, 4.0), rough)
    (0.25, 0.0)
    """
    if not noise > 0:
        return 0.0
    own = np.maximum(np.linalg.eigvalsh(np.asarray(scatter, dtype=np.float64))[:, 0], 0.0) \
        / np.maximum(np.asarray(count, dtype=np.float64), 1.0) if len(count) else np.zeros(0)
    typical = float(np.median(own)) if own.size else 0.0
    return float(min(1.0, noise / typical)) if typical > 0 else 1.0


def _merged(pg, planarity: int, k: int, alpha: float, eta_convex: float, max_rise: float,
            max_size: float, compactness: float = 0.0, min_count: float = 0.0) -> np.ndarray:
    """The merging kernel on a planes' graph, down to ``k`` nodes or as far as it may."""
    n_nodes = pg.n_segments
    if n_nodes == 0:
        return np.zeros(0, dtype=np.int64)
    roots = native.kernel("hierarchy.merge_levels")(
        n_nodes, *merge_arrays(pg, True), planarity, alpha, eta_convex, 0.0, compactness,
        max_rise,
        np.asarray([max(1, min(k, n_nodes))], dtype=np.int64), float(max_size),
        float(min_count))[0]
    _, top = np.unique(roots, return_inverse=True)  # numbered by their lowest superpoint
    return top.astype(np.int64)


def merge_to_count(graph, labels: np.ndarray, rules, features: np.ndarray | None = None
                   ) -> tuple[np.ndarray, int]:
    """Stage 9 where ``rules.params.merge_from > 1``: the flat merges
    (:func:`flat_merges`, up to :data:`FLAT_NOISE` times :func:`noise_variance`), then
    Ward's merges down to ``rules.target`` (:func:`superfacets.method.finish.exact_count`).

    Parameters
    ----------
    graph : ElementGraph
    labels : (n,) int64 ndarray
        Dense labels of the run's ``rules.k`` superpoints.
    rules : Rules
        Its ``target`` is the count asked for.

    Returns
    -------
    labels : (n,) int64 ndarray
        Dense, ``rules.target`` labels (or the input's separate pieces, where more).
    fewest : int
        The count the run could reach.

    Raises
    ------
    ParameterError
        If the labels do not fit the graph.

    Examples
    --------
    >>> xy = np.random.default_rng(0).random((3000, 2))
    >>> r = segment(PointCloud(np.c_[xy, np.zeros(3000)]), 12)   # merge_from: 5
    >>> r.n_segments, r.params["merge_from"]
    (12, 5)
    """
    k = rules.target
    n = int(labels.max()) + 1 if labels.size else 0
    if k is None or n <= k:
        return labels, n
    p = rules.params
    colour = features if p.beta > 0 else None  # the merges join one colour's neighbours
    lab, nodes, pairs = _sums(graph, labels, colour)
    _, final, fewest = merge_nodes(nodes, pairs, k, FLAT_NOISE * noise_variance(graph),
                                   p.alpha, p.eta_convex,
                                   max_jump=None if colour is None else rules.feature_floor,
                                   max_ratio=p.max_size_ratio, cost=p.merge_cost)
    return final[lab], fewest


def _sums(graph, labels: np.ndarray, features=None) -> tuple:
    """Dense int64 ``labels``, and what the merges read of them: per superpoint
    (:func:`~superfacets.graph.sums.point_sums`) and per adjacent pair
    (:func:`~superfacets.graph.sums.border_sums`)."""

    lab = np.ascontiguousarray(check_labels(labels, graph.n_elements, per=graph.element),
                               dtype=np.int64)
    k = int(lab.max()) + 1 if lab.size else 0
    feats = None if features is None else np.asarray(features, dtype=np.float64).reshape(
        graph.n_elements, -1)
    nodes = point_sums(lab, k, graph.positions, real_rows(graph.normals), graph.sizes, feats)
    return lab, nodes, border_sums(graph, lab, k)


def merge_nodes(nodes: dict, pairs: dict, target: int, max_rise: float | None,
                alpha: float, eta_convex: float, *, max_jump: float | None = None,
                max_ratio: float = 0.0, cost: str = "auto"
                ) -> tuple[np.ndarray, np.ndarray, int]:
    """Both phases of :func:`merge_to_count` on the superpoints' sums (one run's, or a
    tiled run's added over its tiles: the same merges).

    Parameters
    ----------
    nodes : dict
        Per superpoint, :func:`superfacets.graph.sums.point_sums`.
    pairs : dict
        Per adjacent pair, :func:`superfacets.graph.sums.border_sums` (a pair may repeat:
        its sums are added).
    target : int
        The count asked for, ``>= 1``.
    max_rise : float or None
        The flat merges' threshold (:func:`flat_merges`); None: no flat merges (no noise
        read: a tiled mesh), Ward's merges alone.
    alpha, eta_convex : float
        The crease factor of Ward's cost (paper eqs. 2-3).
    max_jump : float, optional
        With the nodes' ``feature_sum`` and ``feature_squares``: the flat merges join only
        neighbours of one colour (:func:`same_feature_edges`).
    max_ratio : float, default 0
        ``> 0``: the flat merges and the plane's rise make no superpoint of more than
        this many times the mean count (the elements over ``target``) while another pair
        may merge (the parameter ``max_size_ratio``); 0: no bound.
    cost : {'auto', 'scene', 'noise'}, default 'auto'
        Phase 2's (the parameter ``merge_cost``,
        :data:`superfacets.method.params.MERGE_COSTS`): ``'scene'`` merges by
        :func:`scene_merge_nodes` on every input (with ``max_rise``; without it, Ward's);
        ``'noise'`` likewise, its rise weighted by :func:`rise_weight`, where the noise is
        above 0 (``max_rise > 0``), else ``'auto'``'s rule (a noise-free sampled surface:
        the same merges).

    Returns
    -------
    flat : (K,) int64 ndarray
        Each superpoint's group after the flat merges.
    final : (K,) int64 ndarray
        Each superpoint's label, dense.
    fewest : int
        The count reached: ``target``, or the separate pieces where there are more (or
        the superpoints, where fewer).

    Raises
    ------
    ParameterError
        Never on sums of valid labels.

    Examples
    --------
    >>> from superfacets.graph.sums import PAIR_FIELDS
    >>> nodes = dict(count=np.ones(3), mean=np.eye(3), scatter=np.zeros((3, 3, 3)),
    ...              area=np.ones(3), area_mean=np.eye(3))
    >>> pairs = dict(edges=np.array([[0, 1], [1, 2]]), **dict(zip(PAIR_FIELDS, np.ones((6, 2)))))
    >>> flat, final, fewest = merge_nodes(nodes, pairs, 2, None, 0.0, 0.0)
    >>> sorted(np.bincount(final).tolist()), fewest
    ([1, 2], 2)
    """

    count = nodes["count"]
    k = count.shape[0]
    flat = np.arange(k)
    # the largest superpoint the merges may make while others can merge (0: any)
    cap = max_ratio * float(count.sum()) / target if max_ratio > 0 else 0.0
    if max_rise is not None:
        flat = flat_merge_nodes(_planes_graph(nodes, pairs, None, max_jump), target, max_rise,
                                alpha, eta_convex, cap, FLAT_MIN_ELEMENTS)
    n_flat = int(flat.max()) + 1 if k else 0
    if not n_flat:
        return flat, flat, 0
    if max_rise is not None and (cost == "scene" or cost == "noise" and max_rise > 0):
        noise = max_rise / FLAT_NOISE
        weight = 1.0 if cost == "scene" else rise_weight(noise, count, nodes["scatter"])
        final, fewest = _scene_merges(nodes, pairs, flat, target, noise, alpha, eta_convex,
                                      max_jump, cap, weight)
        return flat, final, min(fewest, n_flat)
    if max_rise is not None and flat_share(np.arange(k), flat, count) >= FLAT_SHARE:
        # the plane's rise: among neighbours of one colour first (a board on its wall is
        # flat too), then across colours where the count needs it
        final = flat
        for guard in ((max_jump, None) if max_jump is not None else (None,)):
            graph = _planes_graph(nodes, pairs, final, guard)
            fewest = max(target, pieces(graph))
            if graph.n_segments > fewest and cap > 0:  # under the bound first
                final = rise_merge_nodes(graph, fewest, cap)[final]
                graph = _planes_graph(nodes, pairs, final, guard)
            if graph.n_segments > fewest:
                tree = hierarchy.hierarchy(graph, [fewest], cost="planarity")
                final = tree.labels(0, final).astype(np.int64)
        return flat, final, min(fewest, n_flat)
    area = np.bincount(flat, weights=nodes["area"], minlength=n_flat)
    mean = np.stack([np.bincount(flat, weights=nodes["area"] * nodes["area_mean"][:, c],
                                 minlength=n_flat) for c in range(3)], 1)
    graph = grouped_graph(flat, pairs["edges"], pairs, area,
                          mean / np.where(area > 0, area, 1.0)[:, None])
    fewest = max(target, pieces(graph))
    final = flat
    if n_flat > fewest:
        level = hierarchy.hierarchy(graph, [fewest], alpha=alpha, eta_convex=eta_convex)
        final = level.labels(0, flat).astype(np.int64)
    return flat, final, min(fewest, n_flat)


def _scene_merges(nodes: dict, pairs: dict, flat: np.ndarray, target: int, noise: float,
                  alpha: float, eta_convex: float, max_jump: float | None, cap: float,
                  weight: float = 1.0) -> tuple[np.ndarray, int]:
    """Phase 2 by the scene's cost (:func:`scene_merge_nodes`) from the flat merges' groups:
    among neighbours of one colour first, then across colours; under the size bound first.
    The rise's unit is the scan's noise or the neighbourhoods' residual
    (:func:`ring_residual`), the larger (where both are 0, an exactly planar input, machine
    precision times Ward's), over ``weight`` (0: no rise); Ward's is the superpoint asked
    for's area over pi."""
    size = float(nodes["area"].sum()) / (np.pi * target)
    size = size if size > 0 else 1.0
    final, fewest = flat, target
    for guard in ((max_jump, None) if max_jump is not None else (None,)):
        graph = _planes_graph(nodes, pairs, final, guard)
        fewest = max(target, pieces(graph))
        if graph.n_segments <= fewest:
            continue
        unit = max(noise, ring_residual(graph)) or float(np.finfo(float).eps) * size
        unit = unit / weight if weight > 0 else np.inf
        for bound in ((cap, 0.0) if cap > 0 else (0.0,)):
            if graph.n_segments > fewest:
                final = scene_merge_nodes(graph, fewest, unit, size, alpha, eta_convex,
                                          bound)[final]
                graph = _planes_graph(nodes, pairs, final, guard)
    return final, fewest


def _planes_graph(nodes: dict, pairs: dict, group: np.ndarray | None,
                  max_jump: float | None):
    """The graph of the superpoints grouped by ``group`` ((K,), dense; None: each alone) as
    the flat merges and the plane's rise read it: each group's points' count, mean and
    scatter (its least-squares plane); with ``max_jump``, only its edges between neighbours
    of one colour (:func:`same_feature_edges`)."""
    from dataclasses import replace

    planes = (nodes["count"], nodes["mean"], nodes["scatter"])
    alone = group is None
    if alone:
        group = np.arange(planes[0].size)
    else:
        planes = grouped_planes(group, *planes)
    count = planes[0]
    graph = grouped_graph(group, pairs["edges"], pairs, *planes)
    if max_jump is None:
        return graph
    g = count.shape[0]
    total, squares = (np.stack([np.bincount(group, weights=nodes[f][:, c], minlength=g)
                                for c in range(nodes[f].shape[1])], 1)
                      for f in ("feature_sum", "feature_squares"))
    spread = feature_spread(None, None, g, sums=(count, total, squares))
    colour = total / np.maximum(count, 1.0)[:, None]
    # grouped (the plane's rise), a group smaller than the first superpoints on average
    # joins its neighbours whatever its colour: isolated points of another colour (a
    # photograph's noise) would otherwise stay superpoints of their own
    small = 0.0 if alone else float(count.sum()) / max(group.size, 1)
    return same_feature_edges(replace(graph, feature=colour), max_jump, spread,
                              free_below=small)


def flat_share(fine: np.ndarray, merged: np.ndarray, weights: np.ndarray | None = None
               ) -> float:
    """The share of the elements that lie in flat regions: superpoints of ``merged``
    (phase 1's, :func:`flat_merges`) made of two or more of ``fine``.

    Parameters
    ----------
    fine, merged : (n,) int64 ndarray
        Dense labels; ``merged`` coarsens ``fine``.
    weights : (K,) float ndarray, optional
        Each fine superpoint's elements (a tiled run's sums), instead of counting them
        in ``fine``.

    Returns
    -------
    float
        In ``[0, 1]``; 0 for no elements.

    Examples
    --------
    >>> flat_share(np.array([0, 0, 1, 2, 3, 3]), np.array([0, 0, 0, 1, 2, 2]))
    0.5
    """
    if fine.size == 0:
        return 0.0
    k = int(fine.max()) + 1
    top = np.zeros(k, dtype=np.int64)
    top[fine] = merged  # the merged superpoint of each fine one
    grown = np.bincount(top)[top] >= 2
    size = np.bincount(fine, minlength=k).astype(np.float64) if weights is None else \
        np.asarray(weights, dtype=np.float64)
    total = float(size.sum())
    return float(size[grown].sum()) / total if total > 0 else 0.0
