"""Weights of the element graph: the paper's (eqs. 1-3) and Shlafman et al.'s (eq. 6).

Pure functions of the cached :class:`~superfacets.elements.AdjacencyTerms`
of an element graph, so any element kind with those terms gets the same
weights, and several weightings of one mesh share the geometry.
"""

from __future__ import annotations

import numpy as np

from .._kernels import native
from .._runtime import threads
from .._runtime.arrays import real_rows
from .._runtime.threads import split
from ..checks import check_unmasked
from ..elements.builders import as_element_graph
from ..elements.graph import CHUNK, ElementGraph, chunked
from ..elements.kinds import kind_of
from ..elements.vertices import symmetric_terms
from ..errors import ParameterError
from .params import (
    DEFAULTS,
    MAX_WEIGHT_FACTOR,
    WEIGHTING_ALPHA,
    WEIGHTINGS,
    check_choice,
    check_nonneg,
    check_number,
)

__all__ = ["paper_weights", "shlafman_weights", "edge_weights", "csr_weights", "weight_dtype",
           "csr_point_weights", "check_features", "convex_scaled", "feature_jumps",
           "feature_scale", "feature_sample", "scale_of", "FEATURE_FLOOR_QUANTILE",
           "HeldWeights", "weights_array"]

_PAPER_ALPHA = DEFAULTS.alpha
_SHLAFMAN_ALPHA = WEIGHTING_ALPHA["shlafman"][0]


def paper_weights(graph, *, alpha: float = _PAPER_ALPHA, eta_convex: float = DEFAULTS.eta_convex,
                  features: np.ndarray | None = None, beta: float = 0.0, floor: float = 0.0,
                  dtype=np.float64) -> np.ndarray:
    """Weights of the paper (Simari, Picciau, De Floriani 2014, eqs. 1-3).

    For adjacent faces ``f_i, f_j`` with centroids ``c_i, c_j``, unit normals
    ``n_i, n_j``, shared edge ``e_ij`` of midpoint ``m_ij``:

    - ``geo = |c_i - m_ij| + |m_ij - c_j|`` (eq. 1);
    - ``theta = arccos(n_i . n_j)`` in ``[0, pi]``, the unsigned dihedral angle;
    - ``ang = eta * |e_ij| * theta / pi`` (eq. 2), with ``eta = 1`` on concave
      edges and ``eta_convex`` on convex ones; an edge is concave when
      ``n_i . (c_j - c_i) > 0`` (authors' implementation), ``i < j``;
    - ``w = (geo + alpha * ang) / d`` (eq. 3), ``d`` the bounding-box diagonal;
    - with ``beta > 0``, a feature term in the same form as ``ang`` (not in the
      paper): ``w = (geo + alpha * ang + beta * |e_ij| * jump) / d``, ``jump =
      max(0, ||f_i - f_j|| - floor)`` (:func:`feature_jumps`), ``f`` one feature per
      element (e.g. RGB in ``[0, 1]``), ``floor`` the features' noise between
      neighbours (:func:`feature_scale`): crossing a colour edge costs as crossing a
      crease does (``docs/notes/method.md``, "Features").

    On mesh vertices and cloud points the graph's terms are the analogues
    (``docs/notes/method.md``, section 6): ``geo = |p_i - p_j|``, the angle of the
    element normals, ``ang = eta * |p_i - p_j| * theta / pi`` (``graph.span``)
    and the symmetric convexity test.

    Parameters
    ----------
    graph : ElementGraph, Mesh, trimesh.Trimesh or (vertices, faces)
        The element graph (of a mesh: its cached face graph).
    alpha : float, default 200
        Weight of the angular term, in ``[0, 1e12]``.
    eta_convex : float, default 0.2
        Factor ``eta`` of convex edges, in ``[0, 1e12]``.
    features : (n, d) float ndarray, optional
        One finite feature row per element (needed when ``beta > 0``).
    beta : float, default 0
        Weight of the feature term, in ``[0, 1e12]``; 0 gives the paper's
        weights bit for bit.
    floor : float, default 0
        Feature differences up to it cost nothing (:func:`feature_jumps`), ``>= 0``.
    dtype : numpy dtype, default float64
        Of the result (each weight computed in float64, then stored):
        :func:`weight_dtype`.

    Returns
    -------
    weights : (e,) float64 ndarray
        One weight per adjacency (``graph.pairs`` order), unitless
        (fractions of ``d``), ``>= 0``. Invariant to uniform scaling and
        rigid motion of the mesh.

    Raises
    ------
    ParameterError
        If ``alpha``, ``eta_convex`` or ``beta`` is negative, NaN or infinite,
        or ``beta > 0`` without one finite feature row per element.

    References
    ----------
    Simari, Picciau, De Floriani, "Fast and Scalable Mesh Superfacets", 2014,
    eqs. 1-3; ``docs/notes/method.md``.

    Examples
    --------
    >>> box = trimesh.creation.box()
    >>> w = paper_weights((box.vertices, box.faces), alpha=0)
    >>> w.shape
    (18,)
    """
    alpha = check_number("alpha", alpha, 0.0, MAX_WEIGHT_FACTOR)
    eta_convex = check_number("eta_convex", eta_convex, 0.0, MAX_WEIGHT_FACTOR)
    beta = check_number("beta", beta, 0.0, MAX_WEIGHT_FACTOR)
    floor = check_nonneg("floor", floor)
    g = as_element_graph(graph)
    span = g.span
    f = check_features(features, g) if beta > 0 else None
    g.normals, g.pairs, g.edges  # noqa: B018 (made here if released: chunks on threads)

    def weight(sl):
        t = g.terms_in(sl)
        theta = np.arccos(t.cos)
        eta = np.where(t.concave, 1.0, eta_convex)
        ang = eta * span[sl] * theta / np.pi
        if f is None:
            return (t.geo + alpha * ang) / g.diagonal
        jump = feature_jumps(f, g.pairs[sl], floor)
        return (t.geo + alpha * ang + beta * span[sl] * jump) / g.diagonal

    with np.errstate(over="ignore"):  # (an overflow is refused below, by its name)
        out = chunked(g.n_edges, weight, dtype)
    if f is not None:
        _check_finite_weights(out, beta)
    return out


def convex_scaled(graph, weights: np.ndarray, *, alpha: float, eta_convex: float,
                  factor: float, weighting: str = "paper") -> np.ndarray:
    """The paper's weights (eqs. 1-3) with the angular term of convex edges
    scaled by ``factor`` (0: removed), from the run's CSR weights.

    The swap energies of split-and-merge (:mod:`superfacets.method.splitmerge`) use
    them on faces with ``factor = 0``: concave creases alone count (the minima
    rule: parts meet at concavities).

    Parameters
    ----------
    graph : ElementGraph
    weights : (2 e,) float64 or float32 ndarray
        The run's weights, one per CSR entry of ``graph``
        (:func:`csr_weights` of :func:`paper_weights`, any ``beta``).
    alpha, eta_convex : float
        The parameters ``weights`` were made with.
    factor : float
        The new ``eta_convex`` as a fraction of the old, in ``[0, 1]``.
    weighting : str, default 'paper'
        Other weightings (Shlafman's has no convex/concave distinction) are
        returned unchanged.

    Returns
    -------
    (2 e,) ndarray of the weights' dtype
        ``weights`` less ``(1 - factor) * alpha * eta_convex * |e| * theta / (pi d)``
        on convex edges (concave ones, and the feature term, as they were; each value
        computed in float64, then rounded to the weights' dtype); ``weights`` itself
        where nothing changes.

    References
    ----------
    Simari, Picciau, De Floriani, "Fast and Scalable Mesh Superfacets", 2014,
    eqs. 1-3; Hoffman and Richards, "Parts of recognition", 1984 (the minima
    rule); ``docs/notes/cleanup.md``, "Swap energies".

    Examples
    --------
    >>> g = face_graph(as_mesh(trimesh.creation.box()))   # every fold convex
    >>> w = csr_weights(g, paper_weights(g))
    >>> bool(np.allclose(convex_scaled(g, w, alpha=200, eta_convex=0.2, factor=0.0),
    ...                  csr_weights(g, paper_weights(g, eta_convex=0.0))))
    True
    """
    g = graph
    scale = alpha * eta_convex * (1.0 - float(factor))
    if weighting != "paper" or scale == 0.0:
        return weights
    convex_scaled_csr = native.kernel("terms.convex_scaled_csr")

    t = g.terms
    return convex_scaled_csr(np.ascontiguousarray(weights), g.dual_edge,
                             t.concave, t.cos, g.span, scale / (np.pi * g.diagonal))


def feature_jumps(features: np.ndarray, pairs: np.ndarray, floor: float = 0.0) -> np.ndarray:
    """How far the features of each pair differ beyond ``floor``: ``max(0, ||f_i - f_j||
    - floor)`` (the feature term of :func:`paper_weights` and of the clean-up's cuts).

    Parameters
    ----------
    features : (n, d) float64 ndarray
    pairs : (e, 2) int ndarray
    floor : float, default 0
        The differences within the features' noise (:func:`feature_scale`), which cost
        nothing.

    Returns
    -------
    (e,) float64 ndarray

    Raises
    ------
    IndexError
        If a pair names a row ``features`` does not have.

    Examples
    --------
    >>> f = np.array([[0.0, 0, 0], [0.3, 0.4, 0], [0.3, 0.4, 0.01]])
    >>> feature_jumps(f, np.array([[0, 1], [1, 2]]), floor=0.1).round(3).tolist()
    [0.4, 0.0]
    """
    jump = np.linalg.norm(features[pairs[:, 0]] - features[pairs[:, 1]], axis=1)
    return np.maximum(jump - floor, 0.0) if floor > 0 else jump


#: The share of neighbouring elements whose feature difference is taken for noise: the
#: floor of :func:`feature_scale`. 0.9 over the median (0.5) on the labelled scans
#: (``docs/notes/superpoints-defaults.md``): a wall's shading and a cushion's print stay
#: under it; boards, doors and paint (a tenth of the adjacencies at most) stand above.
FEATURE_FLOOR_QUANTILE = 0.9

#: Adjacencies :func:`feature_scale` reads (evenly spread slices of the pairs)
_SCALE_SAMPLE, _SCALE_SLICE = 1 << 17, 1 << 10


def feature_scale(graph, features: np.ndarray, *, alpha: float = _PAPER_ALPHA,
                  eta_convex: float = DEFAULTS.eta_convex) -> tuple[float, float]:
    """The feature term's weight and floor read from the data (``beta=None``, not in the
    paper).

    The floor is the feature difference that 90 % of the neighbouring pairs do not
    exceed (:data:`FEATURE_FLOOR_QUANTILE`): most adjacencies lie within one surface, so
    it is the features' noise (a scan's colour noise, a wall's shading, a texture), and
    differences up to it cost nothing. The weight ``beta`` makes the term, on average over
    the adjacencies, weigh as much as the geometric terms of eq. 3 together:
    ``beta = mean(geo / |e| + alpha * eta * theta / pi) / mean(jump)``, ``jump`` the
    differences beyond the floor (:func:`feature_jumps`). Read on about 131,000
    adjacencies at most, in 128 slices evenly spread over the graph (points and vertices:
    over its rows, both directions of each adjacency).

    Parameters
    ----------
    graph : ElementGraph
    features : (n, d) float64 ndarray
        One row per element (:func:`check_features`).
    alpha, eta_convex : float
        The run's.

    Returns
    -------
    beta : float
        0 where no difference stands above the floor (features of one value).
    floor : float

    Raises
    ------
    ParameterError
        If the features do not fit the graph.

    Examples
    --------
    >>> g = as_element_graph(trimesh.creation.icosphere(subdivisions=3))
    >>> top = (g.positions[:, 2] > 0)[:, None]  # two colours, one edge between them
    >>> beta, floor = feature_scale(g, np.where(top, [1.0, 0, 0], [0, 0, 1.0]))
    >>> floor, beta > 0
    (0.0, True)
    >>> feature_scale(g, np.ones((g.n_elements, 3)))
    (0.0, 0.0)
    """
    return scale_of(*feature_sample(graph, features, alpha=alpha, eta_convex=eta_convex))


def feature_sample(graph, features: np.ndarray, *, alpha: float = _PAPER_ALPHA,
                   eta_convex: float = DEFAULTS.eta_convex) -> tuple[np.ndarray, np.ndarray]:
    """What :func:`feature_scale` reads of a graph: the geometric terms and the feature
    differences of its evenly spread adjacencies (a tiled run gathers them from its tiles
    and reads one weight and floor for all: :func:`scale_of`). Its parameters and errors
    are :func:`feature_scale`'s; it returns ``(geometric, jump)``, (m,) float64 each: per
    sampled adjacency, ``geo / |e| + alpha * eta * theta / pi`` (paper eq. 3) and the
    feature difference (:func:`feature_jumps`), ``m`` at most about 131,000.

    Examples
    --------
    >>> g = as_element_graph(trimesh.creation.icosphere(subdivisions=3))
    >>> geo, jump = feature_sample(g, np.ones((g.n_elements, 3)))
    >>> geo.shape == jump.shape, float(jump.max())
    (True, 0.0)
    """
    f = check_features(features, graph)
    geometric, jumps = _scale_sample(graph, f, alpha, eta_convex)
    if not jumps:
        return np.zeros(0), np.zeros(0)
    return np.concatenate(geometric), np.concatenate(jumps)


def scale_of(geometric: np.ndarray, jump: np.ndarray) -> tuple[float, float]:
    """The feature term's weight and floor from :func:`feature_sample`'s arrays (one
    graph's, or a tiled run's tiles' together): the floor the
    :data:`FEATURE_FLOOR_QUANTILE` of the differences, the weight the geometric terms'
    mean over the differences' mean beyond it (at most :data:`MAX_WEIGHT_FACTOR`).

    Parameters
    ----------
    geometric, jump : (m,) float64 ndarray

    Returns
    -------
    beta : float
        ``>= 0``; 0 where no difference stands above the floor, or none was sampled.
    floor : float
        In the features' units.

    Raises
    ------
    ParameterError
        Never.

    Examples
    --------
    >>> scale_of(np.ones(20), np.r_[np.zeros(19), 2.0])   # 2 beyond a floor of 0: 1 / 0.1
    (10.0, 0.0)
    """
    if not jump.size:
        return 0.0, 0.0
    floor = float(np.quantile(jump, FEATURE_FLOOR_QUANTILE))
    above = float(np.maximum(jump - floor, 0.0).mean())
    if not above > 0:
        return 0.0, floor
    beta = float(geometric.mean()) / above
    return (min(beta, MAX_WEIGHT_FACTOR) if np.isfinite(beta) else 0.0), floor


def _scale_sample(graph, f: np.ndarray, alpha: float, eta_convex: float) -> tuple[list, list]:
    """The geometric terms (``geo / |e| + alpha * eta * theta / pi``) and the feature
    differences of evenly spread slices of the adjacencies: of the pairs, or, on a graph of
    points or vertices, of the CSR rows (their terms from the positions and normals: the
    pairs, which such a run never builds, are not made for it)."""

    geometric, jumps = [], []
    if graph.terms_of is symmetric_terms:  # points, vertices: span = geo
        indptr, n = graph.indptr, graph.n_elements
        rows = max(1, _SCALE_SLICE * n // max(int(indptr[-1]), 1))  # about a slice a block
        step = max(rows, -(-n // (_SCALE_SAMPLE // _SCALE_SLICE)))
        pos, nor = np.ascontiguousarray(graph.positions), real_rows(graph.normals)
        for r0 in range(0, n, step):
            geo, cos, concave, pairs = _csr_block_terms(graph, pos, nor, r0, min(n, r0 + rows))
            eta = np.where(concave, 1.0, eta_convex)
            geometric.append(1.0 + alpha * eta * np.arccos(cos) / np.pi)
            jumps.append(feature_jumps(f, pairs))
        return geometric, jumps
    e = graph.n_edges
    step = max(_SCALE_SLICE, -(-e // (_SCALE_SAMPLE // _SCALE_SLICE)))
    span = graph.span
    for start in range(0, e, step):
        sl = slice(start, min(e, start + _SCALE_SLICE))
        t = graph.terms_in(sl)
        eta = np.where(t.concave, 1.0, eta_convex)
        with np.errstate(divide="ignore", invalid="ignore"):
            geo = np.where(span[sl] > 0, t.geo / span[sl], 1.0)
        geometric.append(geo + alpha * eta * np.arccos(t.cos) / np.pi)
        jumps.append(feature_jumps(f, graph.pairs[sl]))
    return geometric, jumps


def _csr_block_terms(graph, pos: np.ndarray, nor: np.ndarray, r0: int, r1: int,
                     pairs: bool = True):
    """``(geo, cos, concave, pairs)`` of the CSR entries of rows ``r0:r1`` of a graph of
    points or vertices (compiled, from the positions and normals), ``pairs`` the (row,
    neighbour) of each entry (None unless asked for)."""
    indptr, indices = graph.indptr, graph.indices
    x0, x1 = int(indptr[r0]), int(indptr[r1])
    geo, cos = np.empty(x1 - x0), np.empty(x1 - x0)
    concave = np.empty(x1 - x0, dtype=bool)
    native.kernel("terms.point_terms_csr")(pos, nor, indptr, indices, r0, r1, geo, cos,
                                           concave)
    if not pairs:
        return geo, cos, concave, None
    rows = np.repeat(np.arange(r0, r1), np.diff(indptr[r0:r1 + 1]))
    return geo, cos, concave, np.stack([rows, indices[x0:x1]], 1)


#: The largest feature magnitude taken: differences of features are squared in double
#: precision (whose largest number is about 1.8e308).
MAX_FEATURE = 1e150


def check_features(features, graph: ElementGraph) -> np.ndarray:
    """``features`` as a finite ``(n, d)`` float64 array, one row per element.

    Raises
    ------
    ParameterError
        If it is missing, of another length, or not finite.
    """
    if features is None:
        raise ParameterError("beta > 0 needs features: one row per element (e.g. RGB "
                             "colours in [0, 1]), or an input with colours")
    f = check_unmasked(features, "features")
    if f.dtype == object or not np.issubdtype(f.dtype, np.number) or \
            np.issubdtype(f.dtype, np.complexfloating):  # (a cast would drop a part)
        raise ParameterError(f"features must be real numbers, got dtype {f.dtype}")
    f = f.astype(np.float64).reshape(f.shape[0], -1) if f.ndim >= 1 else f
    if f.ndim != 2 or f.shape[0] != graph.n_elements:
        raise ParameterError(f"features must have one row per {graph.element} "
                             f"({graph.n_elements}), got shape {np.shape(features)}")
    if not np.isfinite(f).all():
        row = int(np.flatnonzero(~np.isfinite(f).all(axis=1))[0])
        raise ParameterError(f"features of {graph.element} {row} are not finite "
                             f"({f[row].tolist()})")
    big = float(np.abs(f).max()) if f.size else 0.0
    if big > MAX_FEATURE:  # (their differences' squares would overflow double precision)
        raise ParameterError(f"features reach {big:.3g}, beyond {MAX_FEATURE:.0e}: scale them "
                             "(e.g. to [0, 1]); their differences' squares overflow")
    return f


def shlafman_weights(graph, *, alpha: float = _SHLAFMAN_ALPHA, dtype=np.float64) -> np.ndarray:
    """Weights of Shlafman, Tal and Katz, as written in the paper (eq. 6).

    ``w' = (1 - alpha) * geo + alpha * (1 - (n_i . n_j)^2)``, with ``geo`` of
    eq. 1. The roles of ``alpha`` and ``1 - alpha`` are swapped with respect
    to Shlafman et al. so that a higher ``alpha`` favours the angular term, as
    in the paper. Not scale invariant and blind to the concave/convex
    distinction: that is the point of the paper's comparison (Fig. 6).

    Parameters
    ----------
    graph : ElementGraph, Mesh, trimesh.Trimesh or (vertices, faces)
    alpha : float, default 0.5
        In ``[0, 1]``.

    Returns
    -------
    weights : (e,) float64 ndarray
        One weight per adjacency, in mesh units for the geodesic part.

    Raises
    ------
    ParameterError
        If ``alpha`` is outside ``[0, 1]``.

    Examples
    --------
    >>> g = as_element_graph(trimesh.creation.box())
    >>> shlafman_weights(g, alpha=0.5).shape
    (18,)

    References
    ----------
    Simari et al. 2014, eq. 6; Shlafman, Tal, Katz, "Metamorphosis of
    polyhedral surfaces using decomposition", Eurographics 2002.
    """
    a = check_nonneg("alpha", alpha)
    if a > 1:
        raise ParameterError(f"alpha of the Shlafman weighting must be in [0, 1], got {alpha!r}")
    g = as_element_graph(graph)
    g.normals, g.pairs, g.edges  # noqa: B018 (made here if released: chunks on threads)

    def weight(sl):
        t = g.terms_in(sl)
        return (1.0 - a) * t.geo + a * (1.0 - t.cos * t.cos)

    return chunked(g.n_edges, weight, dtype)


def edge_weights(graph, weighting: str = "paper", *, alpha: float = _PAPER_ALPHA,
                 eta_convex: float = DEFAULTS.eta_convex, features: np.ndarray | None = None,
                 beta: float = 0.0, floor: float = 0.0, dtype=np.float64) -> np.ndarray:
    """:func:`paper_weights` or :func:`shlafman_weights` by name.

    Parameters
    ----------
    graph : ElementGraph, Mesh, trimesh.Trimesh or (vertices, faces)
    weighting : {'paper', 'shlafman'}, default 'paper'
    alpha, eta_convex : float
        As the chosen function (``eta_convex`` is ignored by ``'shlafman'``).
    features, beta, floor
        The feature term of :func:`paper_weights` (``'paper'`` only).
    dtype : numpy dtype, default float64
        Of the result (:func:`weight_dtype`).

    Returns
    -------
    weights : (e,) ndarray of ``dtype``

    Raises
    ------
    ParameterError
        On an unknown ``weighting`` or a parameter out of range.

    Examples
    --------
    >>> g = as_element_graph(trimesh.creation.box())
    >>> w = edge_weights(g, "paper", alpha=200)
    >>> w.shape, bool((w > 0).all())
    ((18,), True)
    """
    check_choice("weighting", weighting, WEIGHTINGS)
    if weighting == "paper":
        return paper_weights(graph, alpha=alpha, eta_convex=eta_convex, features=features,
                             beta=beta, floor=floor, dtype=dtype)
    if beta:
        raise ParameterError("beta (the feature term) goes with weighting='paper' only")
    return shlafman_weights(graph, alpha=alpha, dtype=dtype)


def csr_weights(graph: ElementGraph, weights: np.ndarray, dtype=np.float64) -> np.ndarray:
    """Per-adjacency ``weights`` laid out per CSR entry of ``graph`` (contiguous; float64
    by default; :func:`weight_dtype` says which a run uses)."""
    # cast before the gather: one array of the CSR size, in the dtype asked for (on
    # threads, compiled: float64 per adjacency into float64 per entry)
    values = np.ascontiguousarray(np.asarray(weights).astype(dtype, copy=False))
    out = np.empty(graph.dual_edge.shape[0], dtype=values.dtype)
    native.kernel("terms.per_entry")(values, graph.dual_edge, out)
    return out


def csr_point_weights(graph: ElementGraph, *, alpha: float = _PAPER_ALPHA,
                      eta_convex: float = DEFAULTS.eta_convex, dtype=np.float64,
                      features: np.ndarray | None = None, beta: float = 0.0,
                      floor: float = 0.0, step: float = 1.0) -> np.ndarray:
    """The paper's weights per CSR entry of a graph whose elements are points with
    normals (cloud points, mesh vertices: ``terms_of`` is their symmetric terms), made
    from the positions, normals and CSR layout alone.

    Equal, bit for bit, to ``csr_weights(graph, paper_weights(graph, ...), dtype)``
    without the pairs, spans or per-pair weights (about 180 bytes per point a point
    graph then never builds).

    Parameters
    ----------
    graph : ElementGraph
        Of points or vertices.
    alpha, eta_convex : float
        As :func:`paper_weights` (checked there: here as given).
    dtype : numpy dtype, default float64
        Of the result (:func:`weight_dtype`).
    features, beta, floor
        The feature term, as :func:`paper_weights` (``beta > 0``: the same values too).
    step : float, default 1
        ``> 1``: the distance ``geo`` between neighbours with the part of their offset
        along their normals weighed ``step`` times, ``sqrt(geo^2 + (step^2 - 1) off^2)``,
        ``off`` the mean of ``|n_i . d|`` and ``|n_j . d|`` (``step_weight``, not in the
        paper); 1 gives the paper's weights bit for bit.

    Returns
    -------
    (2 e,) ndarray of ``dtype``
        One weight per CSR entry, unitless (fractions of the diagonal ``d``).

    References
    ----------
    Simari, Picciau, De Floriani 2014, eqs. 1-3; ``docs/notes/method.md``, section 6.

    Examples
    --------
    >>> g = point_graph(PointCloud(np.random.default_rng(0).random((200, 3)))).graph
    >>> bool((csr_point_weights(g) == csr_weights(g, paper_weights(g))).all())
    True
    """
    combine_weights = native.kernel("terms.combine_weights")

    g = graph
    f = check_features(features, g) if beta > 0 else None
    pos = np.ascontiguousarray(g.positions)
    nor = real_rows(g.normals)  # (points keep float32: read as float64)
    indptr, indices = g.indptr, g.indices
    out = np.empty(indices.shape[0], dtype=dtype)
    # rows in blocks of about CHUNK entries (np.arccos as paper_weights calls it: its
    # values differ from the C library's in the last bit)
    cuts = np.unique(np.r_[np.searchsorted(indptr, np.arange(0, indptr[-1], CHUNK)),
                           indptr.shape[0] - 1])

    compiled = f is not None and f.shape[1] <= 5  # (numpy's norm adds more columns pairwise)
    if compiled:
        feature_weights = native.kernel("terms.feature_weights_csr")
        f = np.ascontiguousarray(f)

    def blocks(b0: int, b1: int) -> None:
        for r0, r1 in zip(cuts[b0:b1], cuts[b0 + 1:b1 + 1]):
            x0, x1 = indptr[r0], indptr[r1]
            geo, cos, concave, pairs = _csr_block_terms(g, pos, nor, r0, r1,
                                                        f is not None and not compiled)
            if step != 1.0:  # (a step off the surface weighed: not in the paper)
                native.kernel("terms.step_terms_csr")(pos, nor, indptr, indices, int(r0),
                                                      int(r1), float(step), geo)
            theta = np.arccos(cos, out=cos)
            if compiled:  # paper_weights' expression, in its order, per CSR entry
                feature_weights(geo, theta, concave, f, indptr, indices, int(r0), int(r1),
                                float(eta_convex), float(alpha), float(beta), float(floor),
                                float(g.diagonal), out[x0:x1])
                continue
            if f is not None:  # paper_weights' expression, in its order
                ang = np.where(concave, 1.0, eta_convex) * geo * theta / np.pi
                jump = feature_jumps(f, pairs, floor)
                out[x0:x1] = (geo + alpha * ang + beta * geo * jump) / g.diagonal
                continue
            # (geo + alpha * eta * geo * theta / pi) / d in one pass, as numpy's would give
            combine_weights(geo, theta, concave, float(eta_convex), float(alpha),
                            float(g.diagonal), out[x0:x1])

    threads.run_ranges(blocks, split(cuts.shape[0] - 1, min_per_thread=1))
    if f is not None:
        _check_finite_weights(out, beta)
    return out


def _check_finite_weights(w: np.ndarray, beta: float) -> None:
    """Refuse weights that the feature term sent past the dtype's range (features of huge
    magnitude: a search over infinite distances never settles)."""
    if not np.isfinite(w).all():
        raise ParameterError(f"the feature term (beta {beta:g}) makes weights too large for "
                             f"{w.dtype} ({np.finfo(w.dtype).max:.3g}): scale the features "
                             "(e.g. to [0, 1]) or lower beta")


def weight_dtype(kind, paper: bool = False):
    """The dtype of a run's weights per CSR entry on elements ``kind`` (a name or an
    :class:`~superfacets.elements.kinds.ElementKind`): float32 where the kinds' table says
    (``single_weights``: faces and points), float64 elsewhere and for the paper's method
    (its labels bit for bit). Distances still add up in float64.

    Examples
    --------
    >>> weight_dtype("points").__name__, weight_dtype("points", paper=True).__name__
    ('float32', 'float64')
    >>> weight_dtype("faces").__name__, weight_dtype("vertices").__name__
    ('float32', 'float64')
    """

    return np.float32 if kind_of(kind).single_weights and not paper else np.float64


class HeldWeights:
    """A run's CSR weights, held for the stages that read them, which a stage may let go
    of where they can be made again.

    The coarse start reads the weights of every element only to make its clusters'
    graph; on a large cloud they are 4 bytes per CSR entry that
    its passes would hold for nothing. Given ``remake``, :meth:`let_go` forgets them and
    :meth:`get` makes them again (the same inputs, the same values, bit for bit).

    Parameters
    ----------
    weights : (2 e,) float ndarray
    remake : callable, optional
        ``remake()`` returns the same weights; None: they are never let go.

    Examples
    --------
    >>> held = HeldWeights(np.ones(4), remake=lambda: np.ones(4))
    >>> held.let_go(); held.get().sum()
    np.float64(4.0)
    """

    __slots__ = ("_weights", "_remake", "remade")

    def __init__(self, weights: np.ndarray, remake=None) -> None:
        self._weights, self._remake = weights, remake
        self.remade = 0  # how many times they were made again

    def get(self) -> np.ndarray:
        """The weights (made again if let go)."""
        if self._weights is None:
            self._weights = self._remake()
            self.remade += 1
        return self._weights

    def let_go(self) -> None:
        """Forget the weights where they can be made again (else keep them)."""
        if self._remake is not None:
            self._weights = None


def weights_array(weights) -> np.ndarray:
    """The CSR weights an ndarray or a :class:`HeldWeights` holds."""
    return weights.get() if isinstance(weights, HeldWeights) else weights
