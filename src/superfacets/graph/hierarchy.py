"""A nested hierarchy of superfacets: adjacent superfacets merged, cheapest first.

Starting from the superfacet graph (:mod:`superfacets.graph.adjacency`), two
adjacent nodes ``A`` and ``B`` are merged greedily, the cheapest pair first,
until each requested number of segments is reached. The cost of a merge is
Ward's (the rise of the area-weighted squared spread of the centroids, what
compactness measures) scaled as the paper's weights scale a crossing:

``cost(A, B) = a_A a_B / (a_A + a_B) * |c_A - c_B|^2 * (1 + alpha * s_AB / pi)
* (1 + beta * |f_A - f_B|)``

with ``a`` the areas, ``c`` the centroids, ``f`` the mean features and
``s_AB`` the border's mean angle times its mean ``eta`` (1 on the concave
share of the border, ``eta_convex`` on the rest; paper eqs. 2-3): merging
across a concave crease costs what crossing it costs the superfacets. Merges
only join adjacent nodes, so every segment of every level is connected when
the superfacets are (the method's default), and the levels are nested.

With ``cost='planarity'`` the cost is instead the rise of the area-weighted
squared distance to each segment's best plane (the smallest eigenvalue of
its scatter, ``SuperfacetGraph.scatter``), times the feature factor: flat
neighbours merge first whatever their size, so a level spends its segments
where the surface bends (objects, vegetation, edges) and leaves floors,
walls and ground in large pieces, as graph-based partitions do. Run on
superpoints several times more than the level wants, it gives content-adaptive
superpoints (``docs/notes/superpoints.md``, "Content-adaptive levels"). On a point
cloud each point weighs one there (:func:`planarity_graph`: the points'
least-squares planes), and ``extent_weight`` adds Ward's term, so that large
flat pieces also pay for their extent (:func:`level_extent_weight`: on scans of
uneven density).

The merging is a compiled kernel (``merge_levels``, C++).

Not in the paper (superpoint hierarchies are what graph networks on scans
use, e.g. Superpoint Transformer's partition); ``docs/notes/superpoints.md``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .._kernels import native
from ..checks import check_int, check_nonneg, counted
from ..elements.density import density_for
from ..elements.kinds import kind_of
from ..elements.labels import check_labels
from ..errors import ParameterError
from .adjacency import SuperfacetGraph, superfacet_graph

__all__ = ["Hierarchy", "hierarchy", "planarity_graph", "level_extent_weight", "pieces",
           "wanted_levels",
           "AUTO_EXTENT_WEIGHT", "ALPHA", "ETA_CONVEX"]

#: The crease factor's defaults, the method's own (``superfacets.DEFAULTS.alpha`` and
#: ``.eta_convex``, eqs. 2-3; the hierarchy sits below the method, which calls it)
ALPHA, ETA_CONVEX = 200.0, 0.2

#: ``extent_weight`` of a planarity level on a point cloud of uneven density (the
#: clouds that get the automatic ``density``: LiDAR sweeps): there, with each
#: point weighing one, sparse far-range points fit a plane for little, and the
#: level merged the far range across its classes; 0.01 lowered its undersegmentation
#: error on sweeps where it raised it on clouds of even density
#: (``docs/notes/superpoints.md``, "Content-adaptive levels").
AUTO_EXTENT_WEIGHT = 0.01


@dataclass(frozen=True)
class Hierarchy:
    """Nested levels of segments over ``K`` superfacets.

    Attributes
    ----------
    levels : tuple of int
        Number of segments of each level, decreasing.
    parents : tuple of (n_i,) int64 ndarrays
        ``parents[0][s]``: the segment of level 0 holding superfacet ``s``;
        ``parents[i][t]``: the segment of level ``i`` holding segment ``t``
        of level ``i - 1``. Segments of each level are numbered ``0..n-1``
        in the order of their lowest superfacet.

    Examples
    --------
    >>> r = segment(trimesh.creation.icosphere(subdivisions=4), 40)
    >>> h = r.hierarchy([10, 3])
    >>> h.levels, h.of_superfacets(1).shape
    ((10, 3), (40,))
    """

    levels: tuple
    parents: tuple

    def of_superfacets(self, level: int) -> np.ndarray:
        """``(K,)`` int64: the segment of level ``level`` of each superfacet."""
        level = check_int("level", level, lo=0, hi=len(self.levels) - 1)
        out = self.parents[0]
        for i in range(1, level + 1):
            out = self.parents[i][out]
        return out

    def labels(self, level: int, labels: np.ndarray) -> np.ndarray:
        """Per-element (or per-row) labels of one level, from the superfacet labels
        ``labels`` (``-1`` rows, such as invalid points, stay ``-1``); a
        :class:`~superfacets.errors.ParameterError` where they are not integers in
        ``-1..K-1``, the superfacets the hierarchy was made of."""
        top = self.of_superfacets(level)
        lab = check_labels(labels, None)
        if lab.size and (lab.min() < -1 or lab.max() >= top.shape[0]):
            raise ParameterError(f"labels must lie in -1..{top.shape[0] - 1} (the "
                                 f"{top.shape[0]} superfacets of the hierarchy), got "
                                 f"{int(lab.min())}..{int(lab.max())}")
        return np.where(lab >= 0, top[np.maximum(lab, 0)], -1)

    def arrays(self) -> dict[str, np.ndarray]:
        """``levels`` and ``parent_<i>`` arrays, for ``np.savez``."""
        out = {"levels": np.asarray(self.levels, dtype=np.int64)}
        out.update({f"parent_{i}": p for i, p in enumerate(self.parents)})
        return out


def hierarchy(graph, levels, *, alpha: float = ALPHA, eta_convex: float = ETA_CONVEX,
              beta: float = 0.0, cost: str = "ward", extent_weight: float = 0.0) -> Hierarchy:
    """Merge adjacent superfacets, cheapest first, into nested levels (module notes).

    Parameters
    ----------
    graph : SuperfacetGraph
        Of the superfacets to merge (:func:`superfacets.graph.adjacency.superfacet_graph`).
    levels : int or sequence of int
        Numbers of segments wanted, each in ``[c, K]`` with ``c`` the number of
        connected pieces of the graph; sorted decreasing, repeats dropped.
    alpha, eta_convex : float
        The crease factor, as the method's weights (eqs. 2-3), ``>= 0``.
    beta : float, default 0
        Weight of the feature difference (``graph.feature``), ``>= 0``.
    cost : {'ward', 'planarity'}, default 'ward'
        Ward's cost with the crease factor (compact segments), or the rise of
        the distance to the best plane (flat regions merged first; needs
        ``graph.scatter``; ``alpha`` and ``eta_convex`` unused).
    extent_weight : float, default 0
        With ``cost='planarity'``: Ward's term (the rise of the weighted spread
        of the centroids, without the crease factor) times this, added to the
        plane's rise, so large flat pieces also pay for their extent: 0 merges
        any coplanar neighbours for nothing; ``>= 0``, dimensionless (both
        terms are weights times squared lengths).

    Returns
    -------
    Hierarchy

    Raises
    ------
    TypeError
        If ``graph`` is not a superfacet graph (``result.graph()``).
    ParameterError
        If a level is out of range (the message gives the range), a factor
        is negative, or ``extent_weight`` is given with Ward's cost.

    Examples
    --------
    >>> r = segment(trimesh.creation.icosphere(subdivisions=4), 40)
    >>> h = r.hierarchy([20, 5])
    >>> h.levels, [int(p.max()) + 1 for p in h.parents]
    ((20, 5), [20, 5])
    """
    if not isinstance(graph, SuperfacetGraph):
        raise TypeError("hierarchy merges a superfacet graph (result.graph(), superfacets."
                        f"graph.adjacency.superfacet_graph), got {type(graph).__name__}")
    alpha = check_nonneg("alpha", alpha)
    eta_convex = check_nonneg("eta_convex", eta_convex)
    beta = check_nonneg("beta", beta)
    extent_weight = check_nonneg("extent_weight", extent_weight)
    if cost not in ("ward", "planarity"):
        raise ParameterError(f"cost must be 'ward' or 'planarity', got {cost!r}")
    if extent_weight > 0 and cost != "planarity":
        raise ParameterError("extent_weight is a term of cost='planarity' (Ward's cost is "
                             f"compact already), got it with cost={cost!r}")
    if cost == "planarity" and graph.scatter is None:
        raise ParameterError("cost='planarity' needs the superfacets' scatter "
                             "(superfacets.graph.adjacency.superfacet_graph gives it)")
    k = graph.n_segments
    wanted = wanted_levels(levels)
    fewest = pieces(graph)
    if wanted[0] > k or wanted[-1] < fewest:
        raise ParameterError(f"levels must lie in [{fewest}, {k}]: the {k} segments they "
                             f"merge make {counted(fewest, 'connected piece')}, and segments "
                             f"stay connected; got {', '.join(map(str, wanted))}")
    if beta > 0 and graph.feature is None:
        raise ParameterError("beta > 0 needs the superfacets' features (graph.feature)")
    roots = native.kernel("hierarchy.merge_levels")(
        k, *merge_arrays(graph, cost == "planarity"), int(cost == "planarity"), alpha,
        eta_convex, beta if graph.feature is not None else 0.0, extent_weight, np.inf,
        np.asarray(wanted, dtype=np.int64))
    parents = []
    prev = np.arange(k)  # the level-before's segment of each superfacet
    for level in roots:
        _, top = np.unique(level, return_inverse=True)  # numbered by lowest superfacet
        parent = np.zeros(int(prev.max()) + 1, dtype=np.int64)
        parent[prev] = top  # each segment of the previous level lies in one of this one
        parents.append(parent)
        prev = top
    return Hierarchy(levels=tuple(wanted), parents=tuple(parents))


def wanted_levels(levels, at_most: int | None = None,
                  names: tuple = ("levels", "n_segments")) -> list[int]:
    """The numbers of segments of a hierarchy's levels, as :func:`hierarchy` takes them:
    distinct, largest first.

    Parameters
    ----------
    levels : int or sequence of int
        Each ``>= 1``.
    at_most : int, optional
        The number of segments the levels merge (a run's ``n_segments``): none may be
        larger.
    names : tuple of str, default ('levels', 'n_segments')
        The two parameters' names, as the message says them (the command line's
        ``('--levels', '-k')``).

    Returns
    -------
    list of int

    Raises
    ------
    ParameterError
        If ``levels`` names no number, or one is not an integer ``>= 1``, or one is larger
        than ``at_most``.

    Examples
    --------
    >>> wanted_levels([30, 100, 30]), wanted_levels(5)
    ([100, 30], [5])
    """
    try:
        wanted = [levels] if np.isscalar(levels) else list(levels)
    except TypeError:
        raise ParameterError("levels must be a number of segments or a sequence of them, "
                             f"got {levels!r}") from None
    if not wanted:
        raise ParameterError("levels must name at least one number of segments")
    wanted = sorted({check_int(names[0], v, lo=1) for v in wanted}, reverse=True)
    if at_most is not None and wanted[0] > at_most:
        raise ParameterError(f"{names[0]} must each be at most the {at_most:,} segments they "
                             f"merge ({names[1]}), got {wanted[0]:,}")
    return wanted


def merge_arrays(graph, planarity: bool) -> tuple:
    """The arrays the merging kernel (``merge_levels``) takes, of a
    :class:`~superfacets.graph.adjacency.SuperfacetGraph`: ``(ea, eb, stats, area, wsum,
    fsum, scatter)``, each a fresh contiguous array (the kernel updates the nodes' in
    place); ``scatter`` as ``(xx, yy, zz, xy, xz, yz)`` with ``planarity``, else zeros."""
    k = graph.n_segments
    area = np.array(graph.area, dtype=np.float64)
    wsum = np.ascontiguousarray(graph.centroid * area[:, None], dtype=np.float64)
    fsum = (np.zeros((k, 0)) if graph.feature is None else
            np.ascontiguousarray(graph.feature * area[:, None], dtype=np.float64))
    scatter = np.zeros((k, 6))
    if planarity:
        m = np.asarray(graph.scatter, dtype=np.float64)
        scatter = np.ascontiguousarray(np.stack([m[:, 0, 0], m[:, 1, 1], m[:, 2, 2], m[:, 0, 1],
                                                 m[:, 0, 2], m[:, 1, 2]], axis=1))
    ln = np.asarray(graph.border_length, dtype=np.float64)
    stats = np.ascontiguousarray(np.stack([ln, ln * graph.mean_angle, ln * graph.concave],
                                          axis=1), dtype=np.float64).reshape(-1, 3)
    edges = np.asarray(graph.edge_index, dtype=np.int64).reshape(2, -1)
    return (np.ascontiguousarray(edges[0]), np.ascontiguousarray(edges[1]), stats, area, wsum,
            fsum, scatter)


def planarity_graph(graph, labels, features=None):
    """The superfacet graph a planarity level merges: that of
    :func:`superfacets.graph.adjacency.superfacet_graph`, but on a point cloud each
    point weighs one (``area`` is the points' count, ``centroid`` and
    ``scatter`` their plain mean and scatter: the points' least-squares
    planes), where a point's estimated area would let the sparse far range
    of a scan weigh most; faces and mesh vertices keep their areas.

    Parameters
    ----------
    graph : ElementGraph
        The run's element graph (``result.elements.graph``).
    labels : (n,) int ndarray
        Superfacet of each element, ``0..K-1``.
    features : (n, d) float ndarray, optional
        As :func:`~superfacets.graph.adjacency.superfacet_graph`.

    Returns
    -------
    SuperfacetGraph

    Raises
    ------
    ParameterError
        If the labels do not fit the graph.

    Examples
    --------
    >>> g = point_graph(PointCloud(np.c_[np.random.default_rng(0).random((500, 2)),
    ...                                   np.zeros(500)])).graph
    >>> planarity_graph(g, np.arange(500) // 250).area.tolist()
    [250.0, 250.0]
    """


    if kind_of(graph.kind).unit_sizes_in_levels:
        graph = graph.replaced(sizes=np.ones(graph.n_elements))
    return superfacet_graph(graph, labels, features)


def level_extent_weight(graph) -> float:
    """``extent_weight`` of a planarity level left to the method.

    :data:`AUTO_EXTENT_WEIGHT` on a point cloud whose point sizes spread like
    those of a scan whose density falls with the range (the cue of the
    automatic ``density``, :func:`superfacets.elements.density.density_for`), 0
    elsewhere (meshes, clouds of even density).

    Parameters
    ----------
    graph : ElementGraph
        The run's element graph (``result.elements.graph``).

    Returns
    -------
    float
        ``AUTO_EXTENT_WEIGHT`` (0.01) or 0.0.

    Raises
    ------
    ParameterError
        Never for a valid graph: nothing is checked beyond it.

    Examples
    --------
    >>> level_extent_weight(segment(trimesh.creation.icosphere(), 10).elements.graph)  # faces
    0.0
    >>> rng = np.random.default_rng(1)   # a dense square, a sparse one beside it
    >>> xy = np.r_[rng.random((3000, 2)), rng.random((200, 2)) + [1.0, 0.0]]
    >>> level_extent_weight(point_graph(PointCloud(np.c_[xy, np.zeros(3200)])).graph)
    0.01
    """

    return AUTO_EXTENT_WEIGHT if density_for(graph) > 0 else 0.0


def pieces(graph) -> int:
    """Connected pieces of the superfacet graph (the fewest segments a level can have).

    Parameters
    ----------
    graph : SuperfacetGraph

    Returns
    -------
    int

    Raises
    ------
    ParameterError
        Never: a superfacet graph is valid by construction.

    Examples
    --------
    >>> pieces(segment(trimesh.creation.icosphere(subdivisions=3), 12).graph())
    1
    """
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    k = graph.n_segments
    a, b = graph.edge_index
    adj = coo_matrix((np.ones(a.shape[0], dtype=np.int8), (a, b)), shape=(k, k))
    return int(connected_components(adj, directed=False)[0]) if k else 0
