"""Content-sensitive element sizes: more superpoints where the points are dense or rough.

The paper's superfacets have equal areas: its radius ``r = sqrt(A / (k pi))``
(section 3.1), its farthest-point centers and its center update (the
size-weighted mean) spread ``k`` centers evenly over the surface. On a real
scan that spends the count where the sensor saw least (the sparse far range
of a LiDAR sweep, flat floor and ground) and leaves few superpoints where the
points and the objects are. Following content-sensitive superpixels (Liu,
Yu, Sun, Ye, "Manifold SLIC", CVPR 2016: superpixels of equal area on a
surface whose area is stretched by the content), each element ``i`` gets a
scale

    s_i = (a~ / a_i)^(q / d) * (1 + c * rho_i)

with ``a_i`` its size (area; a volume for cells), ``a~`` the median size,
``d`` = 2 (3 for cells), ``q = density`` in [0, 1] (0: sizes as they are;
1: every element the same size, i.e. superpoints of equal point counts),
``c = roughness >= 0`` and ``rho_i`` the local roughness: the mean angle
(radians) between the element's normal and its graph neighbours', averaged
twice with the neighbours' (a scan's point normals are noisy one by one).
The run then uses the stretched sizes ``a_i s_i^d`` everywhere it reads a size
(``r``, the center update, the swaps and the clean-up) and places its first
centers by farthest points with each element's distance multiplied by ``s_i``
(:func:`superfacets.method.initialization.farthest_point_centers` reads
``ElementGraph.scale2 = s^2``); the paper's bounded classification, where a
run asks for it (``assignment='bounded'``), gives each center a window of
``2 r / s`` (:func:`window_factors`). Both 0 (the default) change nothing.
``docs/notes/superpoints.md``, "Content-sensitive superpoints", has the measurements.
"""

from __future__ import annotations

import numpy as np

from .._kernels import native
from ..checks import check_int
from .graph import ElementGraph
from .kinds import kind_of

__all__ = ["roughness_of", "content_scale", "adapted_graph", "window_factors", "density_for",
           "size_spread", "AUTO_DENSITY", "AUTO_SPREAD"]

#: Rounds of neighbour averaging of the roughness.
SMOOTH_ROUNDS = 2
#: The most smoothing rounds :func:`roughness_of` takes (each one pass over the pairs).
MAX_ROUNDS = 10_000

#: Rounds of neighbour averaging of the window factors (:func:`window_factors`).
WINDOW_ROUNDS = 4

#: ``density`` of a point cloud whose sizes spread more than :data:`AUTO_SPREAD`
#: (``density=None``, the default: :func:`density_for`).
AUTO_DENSITY = 0.5
#: Standard deviation of the log point sizes above which a cloud's density is uneven:
#: a typical factor of 2 (e^0.7) between the spacings' areas. Points sampled uniformly
#: by area spread 0.31-0.42 (the kNN estimate's own noise: the 300 benchmark meshes at
#: 20,000 points, 0.37 at 500), ScanNet's rooms 0.45, an airborne LiDAR tile 0.21;
#: LiDAR sweeps 1.1, RGB-D frames 0.93-1.09, whose density falls with the range.
AUTO_SPREAD = 0.7


def _neighbour_mean(graph: ElementGraph, x: np.ndarray) -> np.ndarray:
    """``(x_i + sum of x_j over the neighbours j) / (1 + degree)``, from the CSR layout
    (the sums in the order ``x_i + sum_{j > i} + sum_{j < i}`` of ``np.bincount`` over the
    pairs: the same values, without the pairs)."""
    neighbour_mean = native.kernel("terms.neighbour_mean")

    out = np.empty(graph.n_elements)
    neighbour_mean(graph.indptr, graph.indices, np.ascontiguousarray(x, dtype=np.float64), out)
    return out


def roughness_of(graph: ElementGraph, rounds: int = SMOOTH_ROUNDS) -> np.ndarray:
    """Local roughness of each element: the mean angle between its normal and its
    neighbours', averaged ``rounds`` times with the neighbours' values.

    Parameters
    ----------
    graph : ElementGraph
    rounds : int, default 2
        At most :data:`MAX_ROUNDS`.

    Returns
    -------
    (n,) float64 ndarray
        Radians, in ``[0, pi]``; 0 on a plane, 0 for an element without neighbours.

    Raises
    ------
    ParameterError
        If ``rounds`` is not an integer in ``[0, MAX_ROUNDS]``.

    Examples
    --------
    >>> box = trimesh.creation.box()
    >>> rho = roughness_of(as_element_graph((box.vertices, box.faces)), rounds=0)
    >>> round(float(rho.min()), 4), round(float(rho.max()), 4)
    (1.0472, 1.0472)
    """
    rounds = check_int("rounds", rounds, lo=0, hi=MAX_ROUNDS)
    n = graph.n_elements
    lo, hi = graph.pairs[:, 0], graph.pairs[:, 1]
    nor = np.asarray(graph.normals, dtype=np.float64)  # (points keep float32)
    cos = np.einsum("ij,ij->i", nor[lo], nor[hi])
    angle = np.arccos(np.clip(cos, -1.0, 1.0))
    degree = np.bincount(graph.pairs.ravel(), minlength=n)
    rho = (np.bincount(lo, weights=angle, minlength=n) + np.bincount(hi, weights=angle,
                                                                     minlength=n))
    rho /= np.maximum(degree, 1)
    for _ in range(rounds):
        rho = _neighbour_mean(graph, rho)
    return rho


def content_scale(graph: ElementGraph, density: float = 0.0, roughness: float = 0.0
                  ) -> np.ndarray:
    """The scale ``s`` of each element (module notes).

    Parameters
    ----------
    graph : ElementGraph
    density : float, default 0
        Exponent ``q`` in ``[0, 1]``.
    roughness : float, default 0
        Factor ``c >= 0`` of the roughness (per radian).

    Returns
    -------
    (n,) float64 ndarray
        ``s > 0``, unitless; all ones when both are 0.

    Examples
    --------
    >>> x = np.r_[np.linspace(0, 1, 50), np.linspace(2, 6, 50)]   # dense, then sparse
    >>> g = point_graph(PointCloud(np.c_[x, np.zeros((100, 2))]), 4).graph
    >>> s = content_scale(g, density=1.0)
    >>> bool(s[g.positions[:, 0] < 1].mean() > s[g.positions[:, 0] > 2].mean())
    True
    """
    s = np.ones(graph.n_elements)
    if density > 0:
        a = np.asarray(graph.sizes, dtype=np.float64)
        d = float(kind_of(graph.kind).dim)
        positive = a > 0
        med = float(np.median(a[positive])) if positive.any() else 1.0
        s *= (med / np.where(positive, a, med)) ** (density / d)
    if roughness > 0:
        s *= 1.0 + roughness * roughness_of(graph)
    return s


def adapted_graph(graph: ElementGraph, density: float, roughness: float) -> ElementGraph:
    """``graph`` with the stretched sizes ``a s^d`` and ``scale2 = s^2`` (module notes).

    The arrays other than ``sizes`` are shared with ``graph``, which is not
    changed (it may be cached on the input and read by other runs).

    Returns
    -------
    ElementGraph
    """
    s = content_scale(graph, density, roughness)
    d = kind_of(graph.kind).dim
    return graph.replaced(sizes=np.ascontiguousarray(graph.sizes * s ** d),
                          scale2=np.ascontiguousarray(s * s))


def window_factors(graph: ElementGraph, rounds: int = WINDOW_ROUNDS) -> np.ndarray:
    """Factor of each element's squared classification window: ``1 / s^2``,
    averaged ``rounds`` times with the neighbours' values; empty without
    ``graph.scale2`` (the paper's run: one window for all).

    A stretched superfacet of stretched area ``pi r^2`` spans about ``r / s``
    on the surface, so a center on element ``i`` expands within ``window * r
    / s_i`` (:class:`superfacets.method.classify.Classifier`). The sizes of single
    points are noisy (a point a quarter of its neighbours' size would get half
    their window), and elements no window reaches seed superfacets beyond the
    count: on a plane of 6,000 + 750 points at ``density=1``, ``k = 40``, the
    windows of the points' own factors returned 51 superpoints, averaged
    twice 41, four times 40.

    Returns
    -------
    (n,) float64 ndarray, or (0,) float64 ndarray
        Unitless, > 0.

    Examples
    --------
    >>> g = as_element_graph(trimesh.creation.box())
    >>> # 1 / (1 + pi / 3)^2 where each element's mean angle is pi / 2
    >>> window_factors(g).shape, window_factors(adapted_graph(g, 0.0, 1.0)).round(4)[:2]
    ((0,), array([0.2386, 0.2386]))
    """
    if graph.scale2 is None:
        return np.empty(0)
    w = 1.0 / graph.scale2
    for _ in range(rounds):
        w = _neighbour_mean(graph, w)
    return np.ascontiguousarray(w)


def size_spread(graph: ElementGraph) -> float:
    """Standard deviation of the natural log of the positive element sizes (0 if
    fewer than two): how unevenly a cloud's points are spaced, whatever its scale."""
    a = np.asarray(graph.sizes, dtype=np.float64)
    a = a[a > 0]
    return float(np.log(a).std()) if a.shape[0] > 1 else 0.0


def density_for(graph: ElementGraph, paper: bool = False) -> float:
    """The ``density`` of a run that leaves it to the method (``density=None``).

    :data:`AUTO_DENSITY` on a point cloud whose sizes spread beyond
    :data:`AUTO_SPREAD` (:func:`size_spread`): a scan whose density falls with
    the range, where equal areas would spend the count on the sparse far range
    (on two LiDAR sweeps ``density=0.5`` lowered the undersegmentation error by
    13-36 % at 300-3,000 superpoints, ``docs/notes/superpoints.md``). 0 elsewhere:
    meshes (their superfacets keep the paper's equal areas), clouds of even
    density (every cloud sampled from the benchmark's meshes), ``paper=True``.

    Returns
    -------
    float
        ``AUTO_DENSITY`` or 0.0.

    Examples
    --------
    >>> rng = np.random.default_rng(0)
    >>> even = rng.random((4000, 2))
    >>> uneven = np.r_[even * [0.5, 1], rng.random((300, 2)) * [0.5, 1] + [0.5, 0]]
    >>> [density_for(point_graph(PointCloud(np.c_[xy, np.zeros(len(xy))])).graph)
    ...  for xy in (even, uneven)]
    [0.0, 0.5]
    """
    if paper or not kind_of(graph.kind).auto_density:
        return 0.0
    return AUTO_DENSITY if size_spread(graph) > AUTO_SPREAD else 0.0
