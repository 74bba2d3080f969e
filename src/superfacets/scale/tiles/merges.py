"""The merges to the count (:mod:`superfacets.method.merges`) in a tiled run.

A tiled run on a cloud of even density segments ``merge_from`` times the superpoints
asked for, as one run does, and merges them down to the count once every tile has its
labels; a tiled mesh segments a few more than asked (its tiles' cores end with fewer
centers than their shares) and merges them by Ward's merges alone. No process holds the
whole graph, so each tile sums what the merges read, on its own labels
(:func:`tile_merge_stats`, in the labels phase):

- per superpoint, over the tile's core points: their count, mean and scatter about
  that mean (the least-squares plane of the flat merges), and their area and
  area-weighted mean (Ward's merges);
- per pair of adjacent superpoints, over the point graph's adjacencies that cross from
  one to the other: the border length, and the border-weighted angle and concave
  share of the normals (each adjacency counted by one tile only: the one whose core
  holds its point of lower row); an adjacency whose other point lies outside that core
  is sent as it is (the rows of its points), and this process names its two ends by
  the stitched labels: another tile labels that point, and where the two tiles
  disagree on it, this tile's label would pair superpoints that do not touch, whose
  merge would leave a superpoint in two pieces (seen: 2 in 4 clouds of 5M points);
- the noise: the smallest eigenvalue of the neighbourhoods of some core points,
  evenly spaced (:func:`superfacets.method.merges.neighbourhood_noise`).

This process adds the tiles' sums (the scatters by Chan's rule for the union of two
samples), builds the superpoint graph, and merges as one run does
(:func:`merge_names`): the flat merges up to the noise (the median of the tiles'
eigenvalues), then the plane's rise or Ward's merges down to the count, none making a
superpoint above ``max_size_ratio`` times the mean while others can merge. An element
two tiles labelled differently (the run's ``disagreements``) counts under its own tile's
label in that tile's point sums: those are the stitched labels' up to those few elements.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from ..._runtime.arrays import real_rows, row_table
from ...elements.kinds import kind_of
from ...elements.labels import check_labels
from ...errors import ParameterError
from ...graph.adjacency import crossing_adjacencies
from ...graph.hierarchy import Hierarchy, hierarchy
from ...graph.learning import elevation, ground_cells, learning_layout
from ...graph.sums import (
    PAIR_FIELDS,
    area_moments,
    border_sums,
    grouped_graph,
    grouped_planes,
    pair_sums,
    point_sums,
)
from ...method.merges import FLAT_NOISE, merge_nodes, neighbourhood_noise, noise_of
from ...method.rules import merge_from_of

__all__ = ["tile_merge_stats", "merge_names", "one_position_stats", "tiled_merge_from",
           "merged_labels", "tiled_hierarchy", "tiled_learning"]


def tile_merge_stats(graph, labels: np.ndarray, names: np.ndarray, core: np.ndarray,
                     rows: np.ndarray, n_noise: int, *, features: np.ndarray | None = None,
                     floor: float = 0.0, learning: dict | None = None) -> dict:
    """What the merges read, summed over one tile (see the module notes).

    Parameters
    ----------
    graph : ElementGraph
        The tile's point graph (tile and halo).
    labels : (m,) int64 ndarray
        Dense superpoint of each element, ``0..K-1``.
    names : (K,) int64 ndarray
        The run-wide name of each superpoint (its center's row in the input).
    core : (m,) bool ndarray
        The elements of the tile's core.
    rows : (m,) int64 ndarray
        The row in the input of each element (its first row): which tile counts an
        adjacency.
    n_noise : int
        Core elements to read the noise on (evenly spaced), ``>= 0``.
    features : (m, d) float64 ndarray, optional
        The run's colours (where its colour term is on): their sums go with the
        superpoints, so that the merges join only neighbours of one colour.
    floor : float, default 0
        The tile's colour floor (:func:`superfacets.method.weights.feature_scale`).
    learning : dict, optional
        For the superpoint graph in the learning layout (:func:`tiled_learning`):
        ``frame``, the ground's grid (:func:`superfacets.graph.learning.ground_frame`),
        and ``colours``, the elements' colours (m, 3) or None.

    Returns
    -------
    dict
        ``names`` (K',), ``count`` (K',), ``mean`` (K', 3), ``scatter`` (K', 3, 3),
        ``area`` (K',), ``area_mean`` (K', 3): the superpoints with core elements;
        ``edges`` (E, 2) names, lower first, and per edge ``border``, ``angle`` and
        ``concave`` (border-weighted sums), ``crossings``, ``angle_sum`` and
        ``concave_sum`` (plain sums), of the adjacencies with both ends in the core;
        those with one end outside it one by one: ``outer_rows`` (F, 2) int64, the rows
        of their ends, ``outer_names`` (F, 2) this tile's names of them, and
        ``outer_length``, ``outer_angle``, ``outer_concave`` (F,); ``noise``
        (n_noise',) float64; with ``features``, ``feature_sum`` and ``feature_squares``
        (K', d), and ``floor``; with ``learning``, the superpoints' ``area_normal``,
        ``area_scatter`` and ``area_colour`` (:func:`superfacets.graph.sums.area_moments`)
        and the lowest core element of each cell of the ground's grid, ``ground_keys``
        (G, 2) and ``ground_low`` (G,).

    Raises
    ------
    ParameterError
        If the labels do not fit the graph.

    Examples
    --------
    >>> xy = np.stack(np.meshgrid(np.arange(10.0), np.arange(10.0)), -1).reshape(-1, 2)
    >>> g = point_graph(PointCloud(np.c_[xy, np.zeros(100)])).graph
    >>> lab = (g.positions[:, 0] >= 5).astype(np.int64)
    >>> s = tile_merge_stats(g, lab, np.array([7, 9]), np.ones(100, bool), np.arange(100), 4)
    >>> s["names"].tolist(), s["count"].tolist(), s["edges"].tolist()
    ([7, 9], [50.0, 50.0], [[7, 9]])
    """

    lab = np.ascontiguousarray(check_labels(labels, graph.n_elements, per=graph.element),
                               dtype=np.int64)
    names = np.asarray(names, dtype=np.int64)
    at = np.flatnonzero(core)
    # summed over the whole box with the elements outside the core under one more label
    # (dropped): the core's sums, added in the elements' order as over the core alone,
    # without a copy of the core's positions, normals and sizes
    out = names.size
    nodes = point_sums(np.where(core, lab, out), out + 1, graph.positions,
                       real_rows(graph.normals), graph.sizes, features)
    if learning is not None:  # (what one run's superpoint graph weighs by area)
        nodes.update(area_moments(np.where(core, lab, out), out + 1, graph.positions,
                                  real_rows(graph.normals), graph.sizes, nodes["area_mean"],
                                  learning["colours"]))
    used = np.flatnonzero(nodes["count"][:out] > 0)
    nodes = {f: v[used] for f, v in nodes.items()}
    if learning is not None:
        keys, low = ground_cells(np.asarray(graph.positions, dtype=np.float64)[at],
                                 learning["frame"])
        nodes.update(ground_keys=keys, ground_low=low)

    edges = _inner_sums(graph, lab, core, names)
    # an adjacency with an end outside the core: that end's label is another tile's, and
    # this tile's may differ (a border disagreement), so it goes raw, by rows, named by
    # the stitched labels in the driver (a pair it names must touch: no merged piece cut);
    # the tile counts it where its core holds the end of the lower row
    pc, length, cos, concave = crossing_adjacencies(graph, core.astype(np.int64))
    i, j = pc[:, 0], pc[:, 1]
    outer = (lab[i] != lab[j]) & ((core[i] & (rows[i] < rows[j])) |
                                  (core[j] & (rows[j] < rows[i])))
    i, j, length = i[outer], j[outer], length[outer]
    angle = np.arccos(np.clip(cos[outer], -1.0, 1.0))
    concave = concave[outer].astype(np.float64)
    pick = at[np.unique(np.linspace(0, at.size - 1, min(at.size, n_noise)).astype(np.int64))] \
        if n_noise > 0 and at.size else at[:0]
    colour = {} if features is None else dict(floor=float(floor))
    return dict(names=names[used], **nodes, **edges, **colour,
                outer_rows=np.stack([rows[i], rows[j]], 1).astype(np.int64),
                outer_names=np.stack([names[lab[i]], names[lab[j]]], 1),
                outer_length=length, outer_angle=angle, outer_concave=concave,
                noise=neighbourhood_noise(graph, pick))


def _inner_sums(graph, lab: np.ndarray, core: np.ndarray, names: np.ndarray) -> dict:
    """The adjacencies with both ends in the core that cross ``lab``, summed per pair of
    superpoints and named by ``names``, lower first, in the order of the names (as
    :func:`~superfacets.graph.sums.pair_sums` gives them): the sums of
    :func:`~superfacets.graph.sums.border_sums` (one pass over the graph's layout) with
    every element outside the core under one more label, whose pairs are dropped."""
    out = names.size
    s = border_sums(graph, np.where(core, lab, out), out + 1)
    keep = (s["edges"] < out).all(axis=1)
    e = np.sort(names[s["edges"][keep]], axis=1)
    order = np.lexsort((e[:, 1], e[:, 0]))
    return dict(edges=e[order], **{f: s[f][keep][order] for f in PAIR_FIELDS})


def _outer_sums(stats: list[dict], labels: np.ndarray | None) -> dict:
    """The tiles' adjacencies with an end outside their core, named by the stitched
    ``labels`` (center rows, -1 invalid; None: by each tile's own labels) and summed per
    pair of distinct superpoints (:func:`superfacets.graph.sums.pair_sums`)."""
    rows = np.concatenate([s["outer_rows"] for s in stats]).reshape(-1, 2)
    pair = labels[rows] if labels is not None else \
        np.concatenate([s["outer_names"] for s in stats]).reshape(-1, 2)
    ok = (pair[:, 0] != pair[:, 1]) & (pair >= 0).all(axis=1)
    part = {f: np.concatenate([s[f"outer_{f}"] for s in stats])[ok]
            for f in ("length", "angle", "concave")}

    return pair_sums(pair[ok, 0], pair[ok, 1], part["length"], part["angle"],
                     part["concave"])


def one_position_stats(inp, valid: np.ndarray, name: int, merging: tuple) -> dict:
    """:func:`tile_merge_stats` of a tile whose points all lie at one position (a
    :class:`~superfacets.inputs.cloud.PointCloud` or a mesh, ``valid`` its usable rows,
    ``name`` the row naming its one superpoint, ``merging`` as
    :func:`superfacets.scale.tiles.phases.tile_labels` takes it): that superpoint, of the core's
    points, no scatter, no neighbour (nothing where the core has no usable point)."""
    core, rows, _ = merging
    own = np.flatnonzero(valid & np.asarray(core))
    k = 1 if own.size else 0
    where = inp.points if hasattr(inp, "points") else inp.centroids  # (a mesh: its faces')
    at = np.asarray(where, dtype=np.float64)[own[:k]].reshape(k, 3)
    none = np.zeros(0)
    return dict(names=np.full(k, int(np.asarray(rows)[name]), dtype=np.int64),
                count=np.full(k, float(own.size)), mean=at, scatter=np.zeros((k, 3, 3)),
                area=np.full(k, float(own.size)), area_mean=at,
                edges=np.zeros((0, 2), dtype=np.int64), border=none, angle=none,
                concave=none, crossings=none, angle_sum=none, concave_sum=none, noise=none,
                outer_rows=np.zeros((0, 2), dtype=np.int64),
                outer_names=np.zeros((0, 2), dtype=np.int64), outer_length=none,
                outer_angle=none, outer_concave=none)


def tiled_merge_from(params, kind: str, scene: bool = False) -> int:
    """``merge_from`` of a tiled run: that of one run on the whole input (``scene``: it has
    an up direction), with the density of a tiled run (0 unless given); 1 where sized by
    radius. Points only. (With colour, the tiles' sums carry the colours: the merges join
    only neighbours of one colour.)

    Raises
    ------
    ParameterError
        For ``merge_from`` above 1 on faces.
    """

    if not kind_of(kind).cloud:
        if params.merge_from not in (None, 1):
            raise ParameterError("merge_from above 1: a tiled run merges superpoints of "
                                 "point clouds only")
        return 1
    if params.n_segments is None or params.radius is not None:  # sized by radius
        return 1
    density = 0.0 if params.density is None else params.density
    return merge_from_of(replace(params, density=density), kind, scene=scene)


def merged_labels(labels: np.ndarray, stats: list, target: int, params) -> np.ndarray:
    """A tiled run's stitched labels (center rows; -1 invalid) merged to ``target`` from
    the tiles' sums (:func:`merge_names`), a warning where the input's separate pieces
    are more; a label only a repair made (none of the tiles' sums name it) is kept."""
    names, merged, _, fewest = merge_names(stats, target, params.alpha, params.eta_convex,
                                           labels=labels, max_ratio=params.max_size_ratio,
                                           cost=params.merge_cost)
    if fewest > target:
        import warnings

        warnings.warn(f"{fewest} superpoints for n_segments={target}: the input has {fewest} "
                      "separate pieces, and a superpoint cannot cross from one to another",
                      RuntimeWarning, stacklevel=3)
    if names.size == 0:
        return labels.copy()
    at = row_table(names, labels.size)[labels]  # (each names a row of the input)
    return np.where(at >= 0, merged[at], labels)


def merge_names(stats: list[dict], target: int, alpha: float, eta_convex: float, *,
                labels: np.ndarray | None = None, max_ratio: float = 0.0,
                cost: str = "auto") -> tuple[np.ndarray, np.ndarray, int, int]:
    """Merge a tiled run's superpoints down to ``target`` from the tiles' sums
    (:func:`tile_merge_stats`): the flat merges, then Ward's merges or, where most of the
    points lie in flat regions, the plane's rise
    (:data:`~superfacets.method.merges.FLAT_SHARE`), as
    :func:`superfacets.method.merges.merge_to_count` does in one run (where the tiles read
    no noise, as a mesh's do, Ward's merges only).

    Parameters
    ----------
    stats : list of dict
        One per tile.
    target : int
        The count asked for, ``>= 1``.
    alpha, eta_convex : float
        The crease factor of Ward's cost (paper eqs. 2-3).
    labels : (n_rows,) int64 ndarray, optional
        The stitched labels (center rows, -1 invalid): they name the ends of the
        adjacencies a tile saw leave its core, so that only superpoints that touch in the
        stitched labels merge (a tile's own label of an element in another's core can
        differ). Default: each tile's own labels.
    max_ratio : float, default 0
        The largest superpoint the merges may make while others can merge, in mean
        counts (:func:`superfacets.method.merges.merge_nodes`); 0: no bound.
    cost : {'auto', 'scene', 'noise'}, default 'auto'
        The merges' cost to the count (the parameter ``merge_cost``).

    Returns
    -------
    names : (K,) int64 ndarray
        Every superpoint's name, ascending.
    merged : (K,) int64 ndarray
        The name of the superpoint each is merged into (that of its lowest member).
    flat : int
        Superpoints left after the flat merges.
    fewest : int
        The count reached: ``target``, or the separate pieces where there are more.

    Raises
    ------
    ParameterError
        Never on the tiles' own sums.

    Examples
    --------
    >>> x = np.linspace(0, 1, 40)
    >>> xy = np.stack(np.meshgrid(x, x), -1).reshape(-1, 2)
    >>> roof = np.c_[xy, np.abs(xy[:, 0] - 0.5)]                  # two planes, a ridge
    >>> g = point_graph(PointCloud(roof)).graph
    >>> lab = np.minimum(g.positions[:, 0] * 4, 3).astype(np.int64)  # four strips
    >>> south = g.positions[:, 1] < 0.5                               # two tiles
    >>> stats = [tile_merge_stats(g, lab, np.array([3, 5, 8, 13]), core,
    ...                           np.arange(1600), 10) for core in (south, ~south)]
    >>> names, merged, flat, fewest = merge_names(stats, 2, 200.0, 0.2)
    >>> merged.tolist(), fewest                                       # one per plane
    ([3, 3, 8, 8], 2)
    """

    names, node, nodes, pairs = _summed(stats, labels)
    k = names.size
    noise = np.concatenate([s["noise"] for s in stats])
    max_jump = None
    if noise.size and stats and all("feature_sum" in s for s in stats):  # colour on
        nodes["feature_sum"] = _sum(node, stats, "feature_sum", k)
        nodes["feature_squares"] = _sum(node, stats, "feature_squares", k)
        max_jump = float(np.median([s["floor"] for s in stats]))
    # (no noise read, as on a mesh: Ward's merges only)
    rise = FLAT_NOISE * noise_of(noise) if noise.size else None
    flat, final, fewest = merge_nodes(nodes, pairs, target, rise, alpha, eta_convex,
                                      max_jump=max_jump, max_ratio=max_ratio, cost=cost)
    n_flat = int(flat.max()) + 1 if k else 0
    lowest = np.full(int(final.max()) + 1 if k else 0, k, dtype=np.int64)
    np.minimum.at(lowest, final, np.arange(k))
    return names, names[lowest[final]], n_flat, fewest if k else 0


def _summed(stats: list[dict], labels: np.ndarray | None) -> tuple:
    """The tiles' sums added per superpoint and per pair (as :func:`merge_names` reads
    them): ``names`` (K,), each tile's node of its rows, the nodes' ``count``, ``mean``,
    ``scatter``, ``area``, ``area_mean``, and the pairs' :data:`PAIR_FIELDS` with their
    ``edges`` (E, 2) as nodes (the same pair any number of times)."""
    names = np.unique(np.concatenate([s["names"] for s in stats]))
    k = names.size
    node = [np.searchsorted(names, s["names"]) for s in stats]
    # each superpoint's parts in the tiles, as one grouping (Chan's rule)
    count, mean, scatter = grouped_planes(np.concatenate(node), *(
        np.concatenate([s[f] for s in stats]) for f in ("count", "mean", "scatter")))
    area = _sum(node, stats, "area", k)
    area_mean = _sum(node, stats, "area_mean", k, weight="area") / \
        np.where(area > 0, area, 1.0)[:, None]
    nodes = dict(count=count, mean=mean, scatter=scatter, area=area, area_mean=area_mean)
    sums = [*stats, _outer_sums(stats, labels)] if "outer_rows" in stats[0] else stats
    edges = [np.searchsorted(names, s["edges"]) for s in sums]
    keep = [np.isin(s["edges"], names).all(axis=1) for s in sums]  # (names no core holds)
    pairs = {f: np.concatenate([s[f][ok] for s, ok in zip(sums, keep)]) for f in PAIR_FIELDS}
    pairs["edges"] = np.concatenate([e[ok] for e, ok in zip(edges, keep)]).reshape(-1, 2)
    return names, node, nodes, pairs


def tiled_hierarchy(stats: list[dict], fine: np.ndarray, final: np.ndarray, levels, *,
                    alpha: float, eta_convex: float, cost: str = "ward",
                    extent_weight: float = 0.0, cloud: bool = True) -> Hierarchy:
    """Nested coarser levels of a tiled run's superpoints (superfacets), merged from the
    tiles' sums as one run merges its superpoint graph
    (:func:`superfacets.graph.hierarchy.hierarchy`): each superpoint's area and
    area-weighted mean (Ward's cost) or, on a cloud, its points' count, mean and scatter
    (``cost='planarity'``, as :func:`~superfacets.graph.hierarchy.planarity_graph`), and
    per pair of neighbours their border's length, angle and concave share.

    Parameters
    ----------
    stats : list of dict
        The tiles' sums (:func:`tile_merge_stats`), of the superpoints ``fine`` names.
    fine : (n_rows,) int64 ndarray
        The stitched labels the sums are of (center rows, -1 invalid).
    final : (n_rows,) int64 ndarray
        The run's labels, dense ``0..K-1`` (-1 invalid): each superpoint of ``fine`` lies
        in one (the merges to the count join whole superpoints).
    levels : int or sequence of int
        Numbers of segments, as :func:`~superfacets.graph.hierarchy.hierarchy` takes them.
    alpha, eta_convex : float
        The crease factor (paper eqs. 2-3).
    cost : {'ward', 'planarity'}, default 'ward'
    extent_weight : float, default 0
        With ``'planarity'``.
    cloud : bool, default True
        False for a mesh's faces, whose planarity levels weigh the faces' areas, which the
        sums do not hold: refused.

    Returns
    -------
    Hierarchy
        Over the ``K`` superpoints of ``final``: ``hierarchy.labels(i, final)`` are the
        rows' labels of level ``i``.

    Raises
    ------
    ParameterError
        As :func:`~superfacets.graph.hierarchy.hierarchy` (a level out of range), or
        ``cost='planarity'`` on a mesh.

    Examples
    --------
    >>> x = np.linspace(0, 1, 40)
    >>> xy = np.stack(np.meshgrid(x, x), -1).reshape(-1, 2)
    >>> g = point_graph(PointCloud(np.c_[xy, np.abs(xy[:, 0] - 0.5)])).graph  # a ridge
    >>> lab = np.minimum(g.positions[:, 0] * 4, 3).astype(np.int64)  # four strips
    >>> stats = [tile_merge_stats(g, lab, np.array([3, 5, 8, 13]), np.ones(1600, bool),
    ...                           np.arange(1600), 0)]
    >>> h = tiled_hierarchy(stats, np.array([3, 5, 8, 13])[lab], lab, 2, alpha=200.0,
    ...                     eta_convex=0.2)
    >>> h.parents[0].tolist()                                          # one per plane
    [0, 0, 1, 1]
    """
    if cost == "planarity" and not cloud:
        raise ParameterError("a tiled mesh's levels merge by Ward's cost; planarity levels "
                             "of faces weigh their areas, which the tiles do not sum")
    names, _, nodes, pairs = _summed(stats, fine)
    at = row_table(names, fine.size)[fine]
    of = np.full(names.size, -1, dtype=np.int64)
    of[at[at >= 0]] = final[at >= 0]
    held = of >= 0  # (a superpoint a repair left without rows: out)
    if not held.all():
        ends = held[pairs["edges"]].all(axis=1)
        pairs = {f: v[ends] for f, v in pairs.items()}
        pairs["edges"] = np.cumsum(held)[pairs["edges"]] - 1
        nodes, of = {f: v[held] for f, v in nodes.items()}, of[held]
    k = int(final.max()) + 1 if final.size else 0
    if cost == "planarity":
        planes = grouped_planes(of, nodes["count"], nodes["mean"], nodes["scatter"])
    else:
        area = np.bincount(of, weights=nodes["area"], minlength=k)
        centroid = np.stack([np.bincount(of, weights=nodes["area"] * nodes["area_mean"][:, c],
                                         minlength=k) for c in range(3)], 1) / \
            np.where(area > 0, area, 1.0)[:, None]
        planes = (area, centroid, None)
    graph = grouped_graph(of, pairs["edges"], pairs, *planes)
    return hierarchy(graph, levels, alpha=alpha, eta_convex=eta_convex, cost=cost,
                     extent_weight=extent_weight)


def tiled_learning(stats: list[dict], fine: np.ndarray, final: np.ndarray,
                   frame: tuple) -> dict:
    """A tiled run's superpoint graph in the layout learning pipelines read, from the tiles'
    sums (:func:`tile_merge_stats` with ``learning``): the arrays
    :meth:`SegmentationResult.learning_graph` gives of one run's labels, each
    superpoint's area, centroid, normal, scatter and colour summed over the tiles' parts as
    one run sums its elements (the same values but for the order of the additions), the
    ground read on the cells' lowest elements over every tile.

    Parameters
    ----------
    stats : list of dict
        The tiles' sums, of the superpoints ``fine`` names.
    fine : (n_rows,) int64 ndarray
        The stitched labels the sums are of (center rows, -1 invalid).
    final : (n_rows,) int64 ndarray
        The run's labels, dense ``0..K-1`` (-1 invalid).
    frame : tuple
        The ground's grid (:func:`superfacets.graph.learning.ground_frame`).

    Returns
    -------
    dict
        ``area``, ``centroid``, ``normal``, ``feature`` (where the sums hold the
        elements' colours, ``area_colour``: the mean colour per superpoint, also the last
        three columns of ``x``), and
        :func:`superfacets.graph.learning.learning_layout`'s arrays.

    Raises
    ------
    ValueError
        If the sums hold no ``area_scatter`` (the labels phase ran without ``learning``).

    Examples
    --------
    >>> xy = np.stack(np.meshgrid(np.arange(20.0), np.arange(20.0)), -1).reshape(-1, 2)
    >>> g = point_graph(PointCloud(np.c_[xy, np.zeros(400)])).graph
    >>> lab = (g.positions[:, 0] >= 10).astype(np.int64)
    >>> from superfacets.graph.learning import ground_frame
    >>> frame = ground_frame(g.positions, np.array([0.0, 0, 1]))
    >>> s = tile_merge_stats(g, lab, np.array([7, 9]), np.ones(400, bool), np.arange(400),
    ...                      0, learning=dict(frame=frame, colours=None))
    >>> a = tiled_learning([s], np.array([7, 9])[lab], lab, frame)
    >>> a["x"].shape, a["edge_index"].tolist()
    ((2, 10), [[0, 1], [1, 0]])
    """
    if not any("area_scatter" in t for t in stats):
        raise ValueError("the tiles' sums hold no area moments: run the labels phase with "
                         "learning")
    colours = all("area_colour" in t for t in stats if "area_scatter" in t)
    stats = [_with_moments(t) for t in stats]
    names, node, nodes, pairs = _summed(stats, fine)
    k, n = int(final.max()) + 1 if final.size else 0, names.size
    at = row_table(names, fine.size)[fine]
    of = np.full(n, -1, dtype=np.int64)
    of[at[at >= 0]] = final[at >= 0]
    parts = np.concatenate(node)
    _, _, scatter = grouped_planes(parts, *(np.concatenate([s[f] for s in stats])
                                            for f in ("area", "area_mean", "area_scatter")))
    extra = {"normal": _sum(node, stats, "area_normal", n)}
    if colours:
        extra["colour"] = _sum(node, stats, "area_colour", n)
    held = of >= 0  # (a superpoint a repair left without rows: out)
    ends = held[pairs["edges"]].all(axis=1)
    pairs = {f: v[ends] for f, v in pairs.items()}
    pairs["edges"] = np.cumsum(held)[pairs["edges"]] - 1
    nodes = {f: v[held] for f, v in nodes.items()}
    of, scatter = of[held], scatter[held]
    area, centroid, scatter = grouped_planes(of, nodes["area"], nodes["area_mean"], scatter)
    sums = {f: np.stack([np.bincount(of, weights=v[held][:, c], minlength=k)
                         for c in range(v.shape[1])], 1) for f, v in extra.items()}
    norm = np.linalg.norm(sums["normal"], axis=1)
    normal = np.divide(sums["normal"], norm[:, None], out=np.zeros_like(sums["normal"]),
                       where=norm[:, None] > 1e-12 * max(1.0, float(norm.max(initial=0.0))))
    feature = sums["colour"] / np.where(area > 0, area, 1.0)[:, None] if colours else None
    graph = replace(grouped_graph(of, pairs["edges"], pairs, area, centroid, scatter),
                    normal=normal, feature=feature)
    keys = np.concatenate([s.get("ground_keys", np.zeros((0, 2), np.int64)) for s in stats])
    low = np.concatenate([s.get("ground_low", np.zeros(0)) for s in stats])
    cells, inverse = np.unique(keys.reshape(-1, 2), axis=0, return_inverse=True)
    ground = np.full(cells.shape[0], np.inf)
    np.minimum.at(ground, inverse.ravel(), low)
    count = np.bincount(of, weights=nodes["count"], minlength=k)
    out = learning_layout(graph, count, elevation(centroid, frame, cells, ground), final,
                          frame[0])
    out.update(area=area, centroid=centroid, normal=normal)
    if feature is not None:
        out["feature"] = feature
    return out


def _with_moments(stats: dict) -> dict:
    """A tile's sums with zero area moments where it has none (a tile whose points all lie
    at one position: :func:`one_position_stats`)."""
    if "area_scatter" in stats:
        return stats
    k = stats["names"].size
    return dict(stats, area_normal=np.zeros((k, 3)), area_scatter=np.zeros((k, 3, 3)),
                area_colour=np.zeros((k, 3)))


def _sum(node: list, stats: list, field: str, k: int, weight: str | None = None):
    """The tiles' ``field`` added per node (each row times ``weight`` first)."""
    first = np.asarray(stats[0][field])
    out = np.zeros((k,) + first.shape[1:])
    for at, s in zip(node, stats):
        v = np.asarray(s[field], dtype=np.float64)
        np.add.at(out, at, v if weight is None else v * s[weight][:, None])
    return out
