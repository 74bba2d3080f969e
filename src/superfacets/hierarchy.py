"""A nested hierarchy of superfacets: adjacent superfacets merged, cheapest first.

Starting from the superfacet graph (:mod:`superfacets.adjacency`), two
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
superpoints (``docs/superpoints.md``, "Content-adaptive levels").

Not in the paper (superpoint hierarchies are what graph networks on scans
use, e.g. Superpoint Transformer's partition); ``docs/superpoints.md``.
"""

from __future__ import annotations

import heapq
import math
from dataclasses import dataclass

import numpy as np

from .errors import ParameterError
from .params import check_int, check_nonneg

__all__ = ["Hierarchy", "hierarchy", "planarity_graph", "level_compactness",
           "AUTO_COMPACTNESS"]

#: ``compactness`` of a planarity level on a point cloud of uneven density (the
#: clouds that get the automatic ``density``: LiDAR sweeps): there, with each
#: point weighing one, sparse far-range points fit a plane for little, and the
#: level merged the far range across its classes; 0.01 lowered its undersegmentation
#: error at 300-3,000 superpoints on two sweeps (0.88 -> 0.68 at 300 on frame
#: 000700) where it raised it on the rooms and the airborne tile, of even
#: density (``docs/superpoints.md``, "Content-adaptive levels").
AUTO_COMPACTNESS = 0.01


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
        ``labels`` (``-1`` rows, such as invalid points, stay ``-1``)."""
        lab = np.asarray(labels)
        top = self.of_superfacets(level)
        return np.where(lab >= 0, top[np.maximum(lab, 0)], -1)

    def arrays(self) -> dict[str, np.ndarray]:
        """``levels`` and ``parent_<i>`` arrays, for ``np.savez``."""
        out = {"levels": np.asarray(self.levels, dtype=np.int64)}
        out.update({f"parent_{i}": p for i, p in enumerate(self.parents)})
        return out


def hierarchy(graph, levels, *, alpha: float = 200.0, eta_convex: float = 0.2,
              beta: float = 0.0, cost: str = "ward", compactness: float = 0.0) -> Hierarchy:
    """Merge adjacent superfacets, cheapest first, into nested levels (module notes).

    Parameters
    ----------
    graph : SuperfacetGraph
        Of the superfacets to merge (:func:`superfacets.adjacency.superfacet_graph`).
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
    compactness : float, default 0
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
    ParameterError
        If a level is out of range (the message gives the range), a factor
        is negative, or ``compactness`` is given with Ward's cost.

    Examples
    --------
    >>> import trimesh
    >>> from superfacets import segment
    >>> r = segment(trimesh.creation.icosphere(subdivisions=4), 40)
    >>> h = r.hierarchy([20, 5])
    >>> h.levels, [int(p.max()) + 1 for p in h.parents]
    ((20, 5), [20, 5])
    """
    alpha = check_nonneg("alpha", alpha)
    eta_convex = check_nonneg("eta_convex", eta_convex)
    beta = check_nonneg("beta", beta)
    compactness = check_nonneg("compactness", compactness)
    if cost not in ("ward", "planarity"):
        raise ParameterError(f"cost must be 'ward' or 'planarity', got {cost!r}")
    if compactness > 0 and cost != "planarity":
        raise ParameterError("compactness is a term of cost='planarity' (Ward's cost is "
                             f"compact already), got it with cost={cost!r}")
    if cost == "planarity" and graph.scatter is None:
        raise ParameterError("cost='planarity' needs the superfacets' scatter "
                             "(superfacets.adjacency.superfacet_graph gives it)")
    k = graph.n_segments
    wanted = [levels] if np.isscalar(levels) else list(levels)
    if not wanted:
        raise ParameterError("levels must name at least one number of segments")
    wanted = sorted({check_int("levels", v, lo=1) for v in wanted}, reverse=True)
    pieces = _pieces(graph)
    if wanted[0] > k or wanted[-1] < pieces:
        raise ParameterError(f"levels must lie in [{pieces}, {k}]: {k} superfacets in "
                             f"{pieces} connected piece(s), and segments stay connected; "
                             f"got {', '.join(map(str, wanted))}")
    if beta > 0 and graph.feature is None:
        raise ParameterError("beta > 0 needs the superfacets' features (graph.feature)")

    area = graph.area.astype(np.float64).copy()
    wsum = graph.centroid * area[:, None]  # area-weighted sums, merged by addition
    fsum = None if graph.feature is None else graph.feature * area[:, None]
    # the scatters as 6 floats (xx, yy, zz, xy, xz, yz), merged in plain floats
    scatter = None if cost == "ward" else [
        [float(m[0, 0]), float(m[1, 1]), float(m[2, 2]), float(m[0, 1]), float(m[0, 2]),
         float(m[1, 2])] for m in np.asarray(graph.scatter, dtype=np.float64)]
    nbr: list[dict[int, list[float]]] = [dict() for _ in range(k)]
    for t in range(graph.n_edges):
        a, b = int(graph.edge_index[0, t]), int(graph.edge_index[1, t])
        ln = float(graph.border_length[t])
        stats = [ln, ln * float(graph.mean_angle[t]), ln * float(graph.concave[t])]
        nbr[a][b] = stats
        nbr[b][a] = list(stats)
    version = np.zeros(k, dtype=np.int64)
    owner = np.arange(k)  # union-find: the surviving node of each merged one

    def find(s: int) -> int:
        while owner[s] != s:
            owner[s] = owner[owner[s]]
            s = owner[s]
        return s

    def merged_scatter(a: int, b: int) -> list[float]:
        aa, ab = float(area[a]), float(area[b])
        ca, cb = wsum[a] / max(aa, 1e-300), wsum[b] / max(ab, 1e-300)
        x, y, z = (float(ca[0] - cb[0]), float(ca[1] - cb[1]), float(ca[2] - cb[2]))
        w = aa * ab / max(aa + ab, 1e-300)
        sa, sb = scatter[a], scatter[b]
        return [sa[0] + sb[0] + w * x * x, sa[1] + sb[1] + w * y * y, sa[2] + sb[2] + w * z * z,
                sa[3] + sb[3] + w * x * y, sa[4] + sb[4] + w * x * z, sa[5] + sb[5] + w * y * z]

    def merge_cost(a: int, b: int) -> float:
        if scatter is not None:
            c = max(_plane(merged_scatter(a, b)) - _plane(scatter[a]) - _plane(scatter[b]), 0.0)
            if compactness > 0:
                c += compactness * spread(a, b)
        else:
            c = ward(a, b)
        if beta > 0:
            df = fsum[a] / max(area[a], 1e-300) - fsum[b] / max(area[b], 1e-300)
            c *= 1.0 + beta * float(np.sqrt(np.sum(df * df)))
        return c

    def spread(a: int, b: int) -> float:  # Ward's: the rise of the weighted centroid spread
        aa, ab = area[a], area[b]
        tot = aa + ab
        d2 = float(np.sum((wsum[a] / max(aa, 1e-300) - wsum[b] / max(ab, 1e-300)) ** 2))
        return aa * ab / tot * d2 if tot > 0 else 0.0

    def ward(a: int, b: int) -> float:
        ln, ang, conc = nbr[a][b]
        if ln > 0:
            theta, share = ang / ln, conc / ln
        else:
            theta, share = 0.0, 0.0
        s = theta * (share + eta_convex * (1.0 - share))
        return spread(a, b) * (1.0 + alpha * s / math.pi)

    heap = [(merge_cost(a, b), a, b, 0, 0) for a in range(k) for b in nbr[a] if a < b]
    heapq.heapify(heap)
    parents = []
    live = k
    prev = np.arange(k)  # the level-before's segment of each superfacet
    targets = [v for v in wanted]
    while targets:
        if live == targets[0]:
            roots = np.array([find(s) for s in range(k)])
            _, top = np.unique(roots, return_inverse=True)  # numbered by lowest superfacet
            # each segment of the previous level lies in one segment of this one
            parent = np.zeros(int(prev.max()) + 1, dtype=np.int64)
            parent[prev] = top
            parents.append(parent)
            prev = top
            targets.pop(0)
            continue
        c, a, b, va, vb = heapq.heappop(heap)
        if owner[a] != a or owner[b] != b or version[a] != va or version[b] != vb:
            continue  # stale: one of them merged or changed since
        # merge b into a
        owner[b] = a
        if scatter is not None:  # before the sums change
            scatter[a] = merged_scatter(a, b)
        area[a] += area[b]
        wsum[a] += wsum[b]
        if fsum is not None:
            fsum[a] += fsum[b]
        del nbr[a][b]
        del nbr[b][a]
        for c_, stats in nbr[b].items():
            del nbr[c_][b]
            if c_ in nbr[a]:
                merged = [x + y for x, y in zip(nbr[a][c_], stats)]
            else:
                merged = list(stats)
            nbr[a][c_] = merged
            nbr[c_][a] = list(merged)
        nbr[b] = {}
        version[a] += 1
        for c_ in nbr[a]:
            lo, hi = (a, c_) if a < c_ else (c_, a)
            heapq.heappush(heap, (merge_cost(lo, hi), lo, hi, int(version[lo]),
                                  int(version[hi])))
        live -= 1
    return Hierarchy(levels=tuple(wanted), parents=tuple(parents))


def planarity_graph(graph, labels, features=None):
    """The superfacet graph a planarity level merges: that of
    :func:`superfacets.adjacency.superfacet_graph`, but on a point cloud each
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
        As :func:`~superfacets.adjacency.superfacet_graph`.

    Returns
    -------
    SuperfacetGraph

    Examples
    --------
    >>> import numpy as np
    >>> from superfacets.cloud import PointCloud
    >>> from superfacets.elements.points import point_graph
    >>> g = point_graph(PointCloud(np.c_[np.random.default_rng(0).random((500, 2)),
    ...                                   np.zeros(500)])).graph
    >>> planarity_graph(g, np.arange(500) // 250).area.tolist()
    [250.0, 250.0]
    """
    from dataclasses import replace

    from .adjacency import superfacet_graph

    if graph.kind == "points":
        graph = replace(graph, sizes=np.ones(graph.n_elements))
    return superfacet_graph(graph, labels, features)


def level_compactness(graph) -> float:
    """``compactness`` of a planarity level left to the method: :data:`AUTO_COMPACTNESS`
    on a point cloud whose sizes spread as a scan's whose density falls with the
    range (:func:`superfacets.adaptive.density_for`), 0 elsewhere."""
    from .adaptive import density_for

    return AUTO_COMPACTNESS if density_for(graph) > 0 else 0.0


def _plane(m: list[float]) -> float:
    """The smallest eigenvalue of the symmetric 3 x 3 matrix ``(xx, yy, zz, xy, xz, yz)``
    (the area-weighted squared distance to the best plane of a scatter), in closed form
    (the trigonometric solution of the characteristic cubic), >= 0."""
    xx, yy, zz, xy, xz, yz = m
    off = xy * xy + xz * xz + yz * yz
    q = (xx + yy + zz) / 3.0
    p2 = (xx - q) ** 2 + (yy - q) ** 2 + (zz - q) ** 2 + 2.0 * off
    if p2 <= 1e-300:
        return max(q, 0.0)
    p = math.sqrt(p2 / 6.0)
    a, b, c = (xx - q) / p, (yy - q) / p, (zz - q) / p
    d, e, f = xy / p, xz / p, yz / p
    r = 0.5 * (a * (b * c - f * f) - d * (d * c - f * e) + e * (d * f - b * e))
    phi = math.acos(min(1.0, max(-1.0, r))) / 3.0
    return max(q + 2.0 * p * math.cos(phi + 2.0 * math.pi / 3.0), 0.0)


def _pieces(graph) -> int:
    """Connected pieces of the superfacet graph."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    k = graph.n_segments
    a, b = graph.edge_index
    adj = coo_matrix((np.ones(a.shape[0], dtype=np.int8), (a, b)), shape=(k, k))
    return int(connected_components(adj, directed=False)[0]) if k else 0
