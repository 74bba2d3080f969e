"""One input cut into spatial tiles: the work of one tile.

An input too large for one process is cut into axis-aligned tiles
(:mod:`superfacets.scale.tiles.layout`: balanced boxes, or a regular grid);
each element belongs to the *core* of the tile holding its position, and a
tile is read with a *halo*: every element within ``halo * window * r`` of its
core box (:mod:`superfacets.io.regions`). The run then has two phases, each
one task per tile (:mod:`superfacets.scale.tiles.run` sends them to Dask):

1. **centers** (:func:`tile_centers`): the method runs on the tile and its
   halo, with the radius ``r`` of the whole input (so the tile gets its share
   of the ``k`` superfacets); the centers lying in the core are kept. The
   halo gives the centers near a tile border the neighbours they would have
   had in one run. Together the tiles' kept centers are the run's centers,
   each named by its row in the input.
   Then (:func:`tile_refine`, ``refine`` rounds) each tile runs the passes
   again from the gathered centers within reach, moving only its core's (the
   halo's stay where their own tiles put them), so that the centers near a
   border settle beside their true neighbours, not beside the halo's edge
   (with refine rounds to come, the centers phase runs its start and one pass:
   the rounds run the passes). With refine rounds, the centers phase gives way
   to one run on the survey's even sample of the input (a cloud's points, a mesh's
   face centroids: :func:`sample_start`): the rounds start from its centers.
2. **labels** (:func:`tile_labels`): each tile classifies its elements from
   all the centers within reach (one pass of the paper's bounded expansions,
   centers in one global order), then makes superfacets connected and, with
   the clean-up on, re-places their boundaries, as a single run does after
   its last pass. The labels of the core are kept, named by the center's row.

An expansion reaches elements within ``window * r`` of its center, along
paths that stay within that ball; so with a halo of ``2 * window * r``
(``halo = 2``) every core element sees every center that can reach it,
along every path: its classification is the one the whole input would give
from the same centers. A superfacet crossing a tile border has
one name on both sides: tiles are stitched by construction, and no
superfacet is cut by a border. The connectivity step and the clean-up look
a superfacet's width beyond an element; the default halo's third
``window * r`` covers that, and the run counts the elements of each tile's inner halo whose
label differs from the label their own tile gave them (``disagreements``).
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from ...elements import points
from ...elements.builders import ElementInput, elements_of, prepared
from ...elements.features import colors_or_features, per_element
from ...elements.kinds import kind_of
from ...elements.neighbors import nearest, point_tree
from ...elements.points import distinct_points, kept_diagonal, surface_neighbours
from ...errors import ParameterError
from ...inputs.bounds import column_bounds
from ...inputs.cloud import PointCloud, up_weighted
from ...method.classify import BoundedReplay, Exact, make_classifier
from ...method.connectivity import label_components
from ...method.expansion import Workspaces
from ...method.finish import clean_up, finish
from ...method.initialization import farthest_point_centers
from ...method.params import DEFAULTS, SegmentParams, superfacet_measure
from ...method.passes import final_centers
from ...method.pipeline import pipeline
from ...method.rules import assignment_of, better_method
from ...method.stages import build_graph, resolve_features, resolve_rules, weigh
from ...method.weights import feature_sample
from .graphs import kept_classification
from .layout import gathered_centers
from .merges import one_position_stats, tile_merge_stats

__all__ = ["tile_centers", "sample_start", "start_step", "tile_refine", "tile_labels",
           "tile_connect", "orientation_reference", "HALO",
           "point_areas", "point_sizes", "size_moments", "core_sizes", "oriented_sample",
           "check_tileable", "FREEZE_HALO"]

#: Default halo, in units of ``window * r``. 3 rather than 2: the classification of
#: the core is exact from 2, and the clean-up near a border nearly so from 3 (fewer
#: elements labelled differently by two tiles, a lower error: docs/notes/tiles.md).
HALO = 3.0


def point_areas(points: np.ndarray, core: np.ndarray, n_neighbors: int,
                step: float = 1.0) -> float:
    """Summed area of the ``core`` points of a tile (:func:`point_sizes`)."""
    return float(point_sizes(points, core, n_neighbors, step).sum())


def point_sizes(points: np.ndarray, core: np.ndarray, n_neighbors: int,
                step: float = 1.0) -> np.ndarray:
    """The area of each distinct ``core`` point of a tile, as the point graph sizes them
    (``pi rho^2 / K``, ``rho`` the distance to the ``K``-th distinct neighbour among
    ``points``, or with ``step`` above 1 to the farthest of its neighbours along its
    surface); duplicate points count once."""

    pts, inverse = distinct_points(points)  # duplicates share a position, so a core
    is_core = np.zeros(pts.shape[0], dtype=bool)
    is_core[inverse[core]] = True
    k = int(min(n_neighbors, pts.shape[0] - 1))
    if not is_core.any() or k < 1:
        return np.zeros(0)
    if step != 1 and k >= 3 and pts.shape[0] > k + 1:  # (as the graph's build chooses)
        kth = surface_neighbours(pts, point_tree(pts), k, step)[1][is_core]
    else:
        _, kth, _ = nearest(point_tree(pts), k, np.flatnonzero(is_core))
    return np.pi * kth ** 2 / k


def size_moments(sizes: np.ndarray) -> tuple[int, float, float]:
    """``(n, sum of log a, sum of (log a)^2)`` over the positive ``sizes``: what the
    spread of a cloud's point sizes (:func:`superfacets.elements.density.size_spread`)
    is added up from over tiles."""
    a = np.asarray(sizes, dtype=np.float64)
    a = np.log(a[a > 0])
    return int(a.size), float(a.sum()), float((a * a).sum())


def _valid_rows(inp) -> np.ndarray:
    if isinstance(inp, PointCloud):
        return np.asarray(inp.valid)
    return np.ones(inp.n_faces, dtype=bool)


def _diagonal(inp) -> float:
    """The bounding-box diagonal of a tile's elements, as its element graph has it."""

    if isinstance(inp, PointCloud):
        kept = kept_diagonal(inp)  # (the tile's graph, kept or read: its points lent)
        if kept is not None:
            return kept
        valid = np.asarray(inp.valid)
        lo, hi = column_bounds(inp.points if valid.all() else inp.points[valid])
        return float(np.linalg.norm(hi - lo))
    return float(inp.diagonal)


def check_tileable(params: SegmentParams, colors: bool = True) -> None:
    """Refuse the options that read the whole graph, which no tile holds: the merge of
    small superfacets (``min_elements``), content-sensitive sizes (``density``: the
    median size; ``roughness``). ``density=None`` (automatic) is 0 in a tiled run. Also
    ``beta > 0`` on an input without ``colors`` (the survey's). (The merges to the count,
    ``merge_from``, run after the tiles: :mod:`superfacets.scale.tiles.merges`.)

    Raises
    ------
    ParameterError
        Naming the options, with one line on what to do instead.
    """
    whole = [n for n in ("min_elements", "density", "roughness")
             if getattr(params, n) not in (None, 0, getattr(DEFAULTS, n))]
    if whole:
        raise ParameterError(f"{' and '.join(whole)}: not available in a tiled run (where the "
                             "input fits in memory, one run takes it: segment() or the "
                             "command without --tiles)")
    if params.beta is not None and params.beta > 0 and not colors:
        raise ParameterError("beta > 0 needs colours, and this input has none (a tiled run "
                             "reads the colours of the file, not features=)")


def _tile_params(params: SegmentParams, r: float, diagonal: float, tile_diagonal: float
                 ) -> SegmentParams:
    """The run's parameters for one tile: the whole input's radius ``r``."""
    nr = params.neighbor_radius
    # no automatic density: a tile's spread of sizes is not the whole input's; no merges
    # in a tile: they come after, over all the tiles (superfacets.scale.tiles.merges)
    return replace(params, n_segments=None, radius=r / tile_diagonal, progress=False,
                   density=0.0 if params.density is None else params.density, merge_from=1,
                   neighbor_radius=None if nr is None else nr * diagonal / tile_diagonal)


def tile_centers(inp, core: np.ndarray, params: SegmentParams, r: float, diagonal: float,
                 features=None, floor: float | None = None) -> tuple[np.ndarray, object]:
    """Phase 1: the method on one tile and its halo; the centers in its core.

    Parameters
    ----------
    inp : Mesh or PointCloud
        The tile with its halo.
    core : (n_rows,) bool ndarray
        Which rows of ``inp`` lie in the tile's core.
    params : SegmentParams
        The run's (validated) parameters.
    r : float
        The whole input's superfacet radius (mesh units).
    diagonal : float
        The whole input's bounding-box diagonal (for ``neighbor_radius``).
    features : (n_rows, d) float ndarray, optional
    floor : float, optional
        The colour term's floor, read once over every tile (:func:`tile_colour_sample`),
        with ``params.beta`` that run's weight.

    Returns
    -------
    rows : (c,) int64 ndarray
        Rows of ``inp`` that are centers of the core.
    result : SegmentationResult
        The tile's run.
    """
    d = _diagonal(inp)
    if d <= 0:  # every element of the tile at one position: one superfacet
        return np.flatnonzero(core & _valid_rows(inp))[:1], None
    p = _tile_params(params, r, diagonal, d)
    n = _core_share(inp, core, p, r) if p.init == "farthest" else None
    result = pipeline(inp, p, features=features, n_centers=n, finished=False,
                      feature_floor=floor)
    rows = np.asarray(result.centers, dtype=np.int64)
    return rows[core[rows]], result


#: A tiled cloud's start runs on an even sample of at most this share of its points
#: (:func:`sample_start`): a coarse copy of the cloud, not the cloud again.
START_SHARE = 0.25
#: ... and of at least this many points per center and in all (or the whole sample).
START_POINTS_PER_CENTER = 16
START_MIN_POINTS = 10_000
#: The fewest sample points per center a start runs on (fewer: the tiles sample their
#: own centers). The refine rounds run the passes on every point, so a start on 5 points
#: a center gave the tiled error of the tiles' own centers (``docs/notes/tiles.md``).
START_FEWEST_PER_CENTER = 5


def start_step(n_sample: int, n_rows: int, n_segments: int | None) -> int:
    """The stride that thins a survey's sample of ``n_sample`` points (of a cloud of
    ``n_rows``) for a tiled run's start (:func:`sample_start`) and its normals'
    orientation reference (:func:`orientation_reference`), one sample for both: at most
    :data:`START_SHARE` of the cloud, where that keeps at least :data:`START_MIN_POINTS`
    points and :data:`START_POINTS_PER_CENTER` a center (``n_segments``; None: sized by a
    radius), else 1.

    Examples
    --------
    >>> start_step(1_000_000, 2_000_000, 2_000), start_step(1_000_000, 10_000_000, 2_000)
    (2, 1)
    """
    least = max(START_MIN_POINTS, START_POINTS_PER_CENTER * (n_segments or 0))
    return max(1, min(math.ceil(n_sample / (START_SHARE * max(n_rows, 1))),
                      n_sample // least))


def sample_start(sample: np.ndarray, rows: np.ndarray, n_rows: int, params: SegmentParams,
                 r: float, diagonal: float, cloud=None, up=None, viewpoint=None,
                 kind: str = "points") -> tuple[np.ndarray, np.ndarray] | None:
    """The start of a tiled run: the method on an even sample of the input's positions.

    Replaces the centers phase of :func:`tile_centers`: instead of each tile sampling
    its centers on its box and halo (whose outer edge is an artificial boundary) and
    running a pass, the method runs once, start and passes, on the survey's even sample
    of the input as a cloud (a cloud's points, a mesh's face centroids: every
    ``ceil(n / 2^20)``-th row, thinned to
    at most :data:`START_SHARE` of the cloud where it keeps at least
    :data:`START_MIN_POINTS` points and :data:`START_POINTS_PER_CENTER` points a
    center), with the whole input's radius
    ``r``. Its centers, named by their rows in the input, are where the refine rounds
    (:func:`tile_refine`) start: each tile runs the passes on its elements (a mesh's
    faces, with their dihedral angles) from the centers within reach. The colour term is
    off here (the sample keeps positions only); the rounds read the colours. The
    split-and-merge swaps are the input's kind's (``kind``: on for a mesh's faces, as its
    tiles' own start runs them; off for points), unless ``params`` says.

    Parameters
    ----------
    sample : (s, 3) float64 ndarray
        The survey's sample (:class:`superfacets.io.regions.Survey`), finite positions.
    rows : (s,) int64 ndarray
        The row of each sample point in the input, increasing.
    n_rows : int
        Rows of the input (points or faces).
    params : SegmentParams
        The run's (validated) parameters; ``n_segments`` (the superpoints the tiles
        make) is the number of centers sampled, or None with a ``radius``.
    r : float
        The whole cloud's superpoint radius (its units).
    diagonal : float
        The whole cloud's bounding-box diagonal.
    cloud : PointCloud, optional
        The sample thinned by :func:`start_step` as a cloud with its point graph (the
        orientation reference's: :func:`oriented_sample`), used where it holds as many
        points as that thinned sample (else one is made here).
    up : (3,) float ndarray, optional
        The cloud's up direction (``PointCloud.up``), for the sample's normals.
    viewpoint : (3,) float ndarray, optional
        The scanner's position (``PointCloud.viewpoint``): the sample's normals face it.
    kind : {'points', 'faces'}, default 'points'
        The input's elements (a mesh's sample is its face centroids).

    Returns
    -------
    rows : (c,) int64 ndarray
        Rows of the cloud holding the start's centers, increasing.
    positions : (c, 3) float64 ndarray
        Their positions. None instead of both where the sample is not the whole cloud and
        holds fewer than :data:`START_FEWEST_PER_CENTER` points a center (``n_segments``,
        or the centers ``radius`` asks): the tiles then sample their own centers.

    Examples
    --------
    >>> xy = np.random.default_rng(0).random((4000, 2))
    >>> pts = np.column_stack([xy, np.zeros(4000)])
    >>> rows, pos = sample_start(pts, np.arange(4000), 4000, resolve(n_segments=10),
    ...                          0.18, 1.41)
    >>> len(rows), bool((np.diff(rows) > 0).all())
    (10, True)
    """

    sample = np.asarray(sample, dtype=np.float64)
    if sample.shape[0] < min(START_FEWEST_PER_CENTER * (params.n_segments or 0), n_rows):
        return None  # (fewer points a center than a start needs, and not the whole cloud)
    step = start_step(sample.shape[0], n_rows, params.n_segments)
    sample, rows = sample[::step], rows[::step]
    if cloud is None or cloud.points.shape[0] != sample.shape[0]:  # (not the orientation's)
        cloud = PointCloud(sample, up=up, viewpoint=viewpoint)
    d = _diagonal(cloud)
    if d <= 0 or sample.shape[0] < 3:
        return rows[:1], sample[:1]
    if params.n_segments is None and sample.shape[0] < n_rows:  # (sized by the radius)
        area = float(points.point_graph(cloud, params.n_neighbors).graph.area)  # (kept with it)
        if sample.shape[0] < START_FEWEST_PER_CENTER * area / superfacet_measure(r, 2):
            return None
    p = replace(_tile_params(params, r, diagonal, d), beta=0.0, elements=None,  # (a cloud)
                split_merge=better_method(params, kind)[1])
    n = params.n_segments if p.init == "farthest" else None
    found = np.asarray(pipeline(cloud, p, n_centers=n).centers, dtype=np.int64)
    return gathered_centers([dict(centers=rows[found], positions=sample[found])], params)


#: The refine round moves only the core's centers: those of the halo stay where the
#: gathered centers put them (their own tiles move them) and take no part in a swap, so the
#: passes search again only the cells of the core's (docs/notes/tiles.md, "The halo's
#: centers held"). False: every center in the box moves, as before.
FREEZE_HALO = True


def tile_colour_sample(inp, params: SegmentParams, r: float, diagonal: float):
    """What the colour term's weight and floor are read from, on one tile with its halo
    (:func:`superfacets.method.weights.feature_sample`): ``(geometric, jump)`` ((m,)
    float64 each), or None where the tile has no colours, or not all finite, or its
    elements lie at one position. The run reads one weight and floor from every tile's
    (:func:`superfacets.method.weights.scale_of`), so that two tiles weigh a border alike:
    each tile reading its own made the colour term differ between them, and with it the
    labels at their border (0.2-0.6 % of an airborne town tile's points in 4 and 8 tiles).
    """
    d = _diagonal(inp)
    if d <= 0:
        return None
    src, graph, p = build_graph(inp, _tile_params(params, r, diagonal, d))
    given = colors_or_features(src, None)
    if given is None:
        return None
    feats = per_element(src, given)
    if not np.isfinite(feats).all():
        return None
    alpha = p.alpha if p.weighting == "paper" else DEFAULTS.alpha
    return feature_sample(graph, feats, alpha=alpha, eta_convex=p.eta_convex)


def tile_refine(inp, core: np.ndarray, center_rows: np.ndarray, params: SegmentParams,
                r: float, diagonal: float, features=None, folder=None,
                floor: float | None = None) -> np.ndarray:
    """Phase 1b: the method's passes on one tile from the run's centers within reach;
    the rows of the centers the tile keeps (its own: see below).

    The centers near a tile border came from two tiles' runs, each beside an
    artificial boundary (its halo's edge); from the gathered centers, every
    tile sees the true neighbours of its border centers, and the passes
    (and swaps, with the default method) settle them again. ``folder``: the tile's
    graph folder (None: none kept); where it is given, with the exact assignment
    (clouds), the last pass's classification is kept with the tile's point graph
    (``last_classification``, which its task writes to the folder when the tile is let
    go: :func:`~superfacets.scale.tiles.graphs.keep_classification`) for the labels
    phase: its passes list their centers by row, as the labels phase lists the run's, so
    that phase searches again only the cells of the centers that differ (those of the
    halo, moved by their own tiles). The halo's centers stay where they are through the
    passes (:data:`FREEZE_HALO`): only the core's move, and the tile returns those whose
    superfacets reach its core wherever their centers end (in the halo too: no other tile
    moves them), so no center is lost or kept twice at a border.
    """
    d = _diagonal(inp)
    if d <= 0 or len(center_rows) == 0:
        return np.flatnonzero(core & _valid_rows(inp))[:1]
    p = _tile_params(params, r, diagonal, d)
    src = elements_of(inp, p.elements, n_neighbors=p.n_neighbors,
                      neighbor_radius=p.neighbor_radius)
    m = src.graph.n_elements
    of_row = src.to_rows(np.arange(m))
    elem = of_row[np.asarray(center_rows, np.int64)]
    elem = elem[elem >= 0]
    _, first = np.unique(elem, return_index=True)
    exact = folder is not None and assignment_of(p, src.graph.kind) == "exact"
    order = src.first_rows(np.arange(m)) if exact else None
    start = elem[np.sort(first)]
    in_core = np.zeros(m, dtype=bool)
    in_core[of_row[core & (of_row >= 0)]] = True
    fixed = None
    if FREEZE_HALO:  # the halo's centers stay: their own tiles move them
        fixed = np.zeros(m, dtype=bool)
        fixed[start[~in_core[start]]] = True
    result = pipeline(inp, p, features=features, initial=start, finished=False,
                      order=order, fixed=fixed, feature_floor=floor)
    label, used, dist, classifier = result.classification
    if isinstance(classifier, BoundedReplay):  # its recorded expansions, for the labels
        # phase where the tile is held (its core's centers stay: replayed, not expanded)
        src.graph.__dict__["last_classifier"] = classifier
    if exact and (used.size < 2 or (np.diff(order[used]) > 0).all()):  # (no orphan in
        # the last pass; with the graph: the labels phase reads it there where the tile
        # is held; written to the folder when the tile is let go)
        src.graph.__dict__["last_classification"] = (label, used, dist)
    if fixed is None:
        rows = np.asarray(result.centers, dtype=np.int64)
        return rows[core[rows]]
    # the centers this tile moved (not its halo's) whose superfacets reach its core, where
    # they end: one that crossed into the halo is still this tile's (no other moves it),
    # one an orphan seeded at the box's outer edge is not
    touches = np.zeros(used.size, dtype=bool)
    touches[label[in_core]] = True
    return np.sort(src.first_rows(used[touches & ~fixed[used]]))


def orientation_reference(sample: np.ndarray, n_neighbors: int, up=None) -> tuple:
    """Oriented normals of an even sample of a cloud's points, for its tiles.

    Points that carry no normals and no sensor position get PCA normals,
    oriented by propagation and turned outwards per connected piece
    (:mod:`superfacets.elements.points`). A tile sees a piece cut by its
    halo, whose own mean can turn it the other way than the whole cloud
    does, and propagates the signs over its own box: two tiles can turn
    a point they both hold differently. So the sample the survey keeps
    (every ``ceil(n / 2^20)``-th point, thinned by :func:`start_step`) is
    oriented once, here, as one run would, and every tile turns each of its
    normals to agree with the sample's normal nearest its point
    (``PointCloud(orient_like=...)``), alike in every tile.
    ``up`` (the input's ``PointCloud.up``; LAS files: z) turns the sample's
    pieces to agree with that direction instead of outwards.

    Returns
    -------
    (positions (R, 3), normals (R, 3)) : tuple of float64 ndarray
        Empty arrays when the sample is too small for a point graph.
    """
    graph = oriented_sample(sample, n_neighbors, up)
    if graph is None:
        return np.zeros((0, 3)), np.zeros((0, 3))
    return np.array(graph.positions), np.array(graph.normals, dtype=np.float64)


def oriented_sample(sample: np.ndarray, n_neighbors: int, up=None):
    """The point graph (:class:`~superfacets.elements.graph.ElementGraph`) of the sample
    :func:`orientation_reference` orients, or None when it has fewer than 3 distinct
    points; its ``sizes`` sum to the sample's area as a run reads a cloud's."""

    cloud = sample_cloud(sample, n_neighbors, up)
    return None if cloud is None else points.point_graph(cloud, n_neighbors).graph


def sample_cloud(sample: np.ndarray, n_neighbors: int, up=None):
    """The sample :func:`oriented_sample` orients, as a cloud with its point graph
    (built), or None when it has fewer than 3 distinct points."""

    pts = np.asarray(sample, dtype=np.float64)
    if not _three_distinct(pts):
        return None
    cloud = PointCloud(pts, up=up)
    points.point_graph(cloud, n_neighbors)  # (kept with the cloud)
    return cloud


def _three_distinct(pts: np.ndarray) -> bool:
    """Whether the rows of ``pts`` (n, 3) hold at least three distinct points (one pass
    per point found, not a sort of the rows)."""
    if pts.shape[0] < 3:
        return False
    differs = (pts != pts[0]).any(axis=1)
    if not differs.any():
        return False
    return bool((differs & (pts != pts[np.argmax(differs)]).any(axis=1)).any())


def core_sizes(cloud, core: np.ndarray, n_neighbors: int, step: float = 1.0) -> np.ndarray:
    """The size of each distinct point the ``core`` rows of a tile's cloud hold, read on
    the point graph the tile builds (:func:`point_sizes` reads the same sizes on a tree
    of its own; the graph built here is kept with the cloud for the tile's phases)."""

    # (where tile_graph keeps it)
    el = points.point_graph(prepared(cloud, "points")[1], n_neighbors, step=step)
    at = np.asarray(el.index)[np.flatnonzero(core)]
    held = np.zeros(el.graph.n_elements, dtype=bool)  # (ascending, as np.unique gave them:
    held[at[at >= 0]] = True  # the same sum)
    return np.asarray(el.graph.sizes)[held]


def _core_share(inp, core: np.ndarray, p: SegmentParams, r: float) -> int:
    """Initial centers of a tile such that its core gets its share of the run's.

    Farthest-point sampling puts extra centers on a boundary, and the halo's
    outer boundary is an artificial one: with ``A_tile / (pi r^2)`` centers the
    core would get about 6 % fewer than ``A_core / (pi r^2)`` (measured on
    benchmark meshes). Sampling is incremental, so the tile takes the
    shortest run of samples whose centers in the core number the core's share.
    """

    src = elements_of(inp, p.elements, n_neighbors=p.n_neighbors,
                      neighbor_radius=p.neighbor_radius)
    g = src.graph
    of_row = src.to_rows(np.arange(g.n_elements))
    in_core = np.zeros(g.n_elements, dtype=bool)
    in_core[of_row[core & (of_row >= 0)]] = True
    each = superfacet_measure(r, kind_of(g.kind).dim)
    want = max(1, round(float(g.sizes[in_core].sum()) / each))
    budget = int(min(g.n_elements, max(2 * round(g.area / each), want) + 16))
    hits = np.cumsum(in_core[farthest_point_centers(g, budget, every_piece=not p.paper)])
    return int(min(np.searchsorted(hits, want) + 1, budget))


def tile_labels(inp, center_rows: np.ndarray, params: SegmentParams, r: float,
                diagonal: float, features=None, merging: tuple | None = None, folder=None,
                floor: float | None = None, frame: tuple | None = None,
                unweighted: tuple | None = None):
    """Phase 2: labels of one tile from fixed centers (and, ``merging``, the sums the
    merges to the count read: :func:`superfacets.scale.tiles.merges.tile_merge_stats`).

    Parameters
    ----------
    inp : Mesh or PointCloud
        The tile with its halo.
    center_rows : (c,) int64 ndarray
        Rows of ``inp`` holding the centers within reach, in the run's
        global order (ties of the classification go to the earlier).
    params, r, diagonal, features, floor
        As :func:`tile_centers`.
    merging : tuple, optional
        ``(core, rows, n_noise)``: the rows of the tile's core ((n_rows,) bool), the row
        of each in the input ((n_rows,) int64), and the core points to read the noise
        on.
    folder : str or os.PathLike, optional
        The tile's graph folder, where its refine round kept its last classification
        (:func:`tile_refine`): the classification here starts from it (the same labels).
    frame : tuple, optional
        With ``merging``: the ground's grid of the superpoint graph in the learning layout
        (:func:`superfacets.graph.learning.ground_frame`); the sums then hold what it reads
        (:func:`~superfacets.scale.tiles.merges.tile_merge_stats`' ``learning``, the
        elements' colours where the input has them).
    unweighted : tuple, optional
        With ``merging``: ``(up, up_weight)`` of a run that weighs the up coordinate; the
        sums then also hold, as ``'unweighted'``, those of the same labels on the tile's
        points as given (its positions stretched back, its point graph built again), which
        the levels and the graph in the learning layout read, as one run's result reads
        the cloud as given.

    Returns
    -------
    (n_rows,) int64 ndarray
        The row of the center of each row's superfacet (-1: an invalid
        point). Superfacets seeded on elements no center reached are named by
        their seed's row.
    dict
        With ``merging`` only: the tile's sums, superpoints named by their center's
        row in the input.
    """
    d = _diagonal(inp)
    valid = _valid_rows(inp)
    if d <= 0:  # one position: the first center within reach, else the first row
        name = int(center_rows[0]) if len(center_rows) else int(np.flatnonzero(valid)[0])
        named = np.where(valid, name, -1).astype(np.int64)
        if merging is None:
            return named

        return named, one_position_stats(inp, valid, name, merging)
    # the whole run's stages (superfacets.method.pipeline) with one classification from the
    # fixed centers in place of the initialization and the passes
    src, graph, p = build_graph(inp, _tile_params(params, r, diagonal, d), features)
    p, feats, floor = resolve_features(src, graph, p, features, floor)
    rules = resolve_rules(graph, p, r=r, feature_floor=floor)
    w, _ = weigh(graph, replace(rules, split_merge=False), feats)
    m = graph.n_elements
    of_row = src.to_rows(np.arange(m))
    elem = of_row[np.asarray(center_rows, dtype=np.int64)]
    elem = elem[elem >= 0]
    _, first = np.unique(elem, return_index=True)  # duplicate points: one center
    elem = elem[np.sort(first)]
    centers = np.empty(m, dtype=np.int64)
    centers[:elem.size] = elem
    dist = np.empty(m)
    label = np.empty(m, dtype=np.int32)
    spaces = Workspaces(m, w, p.n_threads)
    try:
        classifier = _replaying(graph, w, rules.window_r2, spaces) or make_classifier(
            rules.params.assignment, graph, w, rules.window_r2, spaces)
        last = None if folder is None or not isinstance(classifier, Exact) else \
            kept_classification(folder, m, graph)
        if last is not None:  # the refine round's last pass, its centers listed by row too:
            label, before, dist = last  # only the cells of the centers that differ searched
            classifier.resume(before, dist, label)
        k, _ = classifier.classify(centers, elem.size, dist, label)
    finally:
        spaces.close()
    classifier = None  # (its records, about 60 bytes a face: let go before the clean-up)
    labels, kept = finish(graph, label, centers[:k], rules)
    if rules.cleanup:  # (a piece the clean-up leaves with no neighbour is a superfacet of
        labels = clean_up(graph, labels, kept, rules, feats)  # its own: a center each)
        kept = final_centers(labels, kept, graph.sizes, graph.positions)
    name = src.first_rows(kept)  # each superfacet named by its center's row
    out = src.to_rows(labels)
    named = np.where(out >= 0, name[np.maximum(out, 0)], -1).astype(np.int64)
    if merging is None:
        return named

    core, rows, n_noise = (np.asarray(x) for x in merging)
    first = src.first_rows(np.arange(m))  # each element's first row
    learning = None if frame is None else dict(frame=frame, colours=None if src.colors()
                                               is None else per_element(src, src.colors()))
    stats = tile_merge_stats(graph, labels, rows[name], core[first], rows[first],
                             int(n_noise), features=feats, floor=rules.feature_floor,
                             learning=learning)
    if unweighted is not None:
        stats["unweighted"] = _unweighted_stats(inp, unweighted, src.to_rows(labels),
                                                (rows[name], core, rows, int(n_noise)),
                                                (p, features, rules.feature_floor, frame))
    return named, stats


def _unweighted_stats(inp, weighing: tuple, row_labels: np.ndarray, where: tuple,
                      how: tuple) -> dict:
    """The merges' sums of a tile's labels on its points as given: the tile (read
    stretched along ``up`` by ``up_weight``, ``weighing``) stretched back, its point graph
    built again (as one run's result builds the cloud as given), each element labelled as
    its first row. ``where``: the superpoints' names, the core, the rows and the noise's
    points; ``how``: the tile's parameters, features, feature floor and ground frame."""
    up, weight = weighing
    names, core, rows, n_noise = where
    p, features, floor, frame = how
    flat = up_weighted(replace(inp, up=np.asarray(up, dtype=np.float64)), 1.0 / weight)
    src, graph, p = build_graph(flat, p, features)
    p, feats, floor = resolve_features(src, graph, p, features, floor)
    first = src.first_rows(np.arange(graph.n_elements))
    learning = None if frame is None else dict(frame=frame, colours=None if src.colors()
                                               is None else per_element(src, src.colors()))
    return tile_merge_stats(graph, row_labels[first], names, core[first], rows[first],
                            n_noise, features=feats, floor=floor, learning=learning)


def _replaying(graph, w: np.ndarray, window_r2: float, spaces: Workspaces):
    """The refine round's bounded classifier kept with a held tile's ``graph``
    (:func:`tile_refine`), given the labels phase's ``spaces``, where it classified with
    these very weights and window: the expansions of the centers its last pass shared
    with the labels phase's list (the core's) are replayed, the others' run, the same
    labels as a fresh classification (:class:`~superfacets.method.classify.BoundedReplay`).
    None where there is none (the tile was not held, or was read again)."""
    kept = graph.__dict__.pop("last_classifier", None)
    if not isinstance(kept, BoundedReplay) or kept.w is not w or kept.m != graph.n_elements \
            or kept.indptr is not graph.indptr or kept.window_r2 != float(window_r2):
        return None
    kept.spaces = spaces
    return kept


def tile_connect(inp, labels: np.ndarray, owned: np.ndarray, owned_rows: np.ndarray,
                 params: SegmentParams) -> np.ndarray | None:
    """Phase 3 (only after border disagreements): make this tile's superfacets connected.

    Two tiles that label a border element differently can leave a superfacet
    in pieces once their cores are stitched. A superfacet whose center lies in
    this tile's core lies well inside its halo, so its pieces are found here
    as in the whole input; each piece but the one holding the center (else
    the largest) joins the adjacent superfacet with which it shares the
    longest border (as :func:`~superfacets.method.connectivity.enforce_connectivity`;
    a piece touching only other stray pieces waits for them).

    Parameters
    ----------
    inp : Mesh or PointCloud
        The tile with its halo.
    labels : (n_rows,) int64 ndarray
        The stitched labels of its rows (names: the centers' rows in the
        input; -1 for an invalid point).
    owned : (c,) int64 ndarray
        The names of the superfacets whose center lies in the core.
    owned_rows : (c,) int64 ndarray
        The row of ``inp`` holding each one's center.
    params : SegmentParams

    Returns
    -------
    (n_rows,) int64 ndarray or None
        The labels with the stray pieces of owned superfacets renamed; None
        when there is none (the usual case).
    """

    kind, data = prepared(inp, params.elements)
    if kind_of(kind).cloud:  # the adjacency alone: the normals' signs are not read
        src = ElementInput(*points.point_graph(data, params.n_neighbors, params.neighbor_radius,
                                               oriented=False, step=params.step_weight or 1.0),
                           data)
    else:
        src = elements_of(data, kind, n_neighbors=params.n_neighbors,
                          neighbor_radius=params.neighbor_radius)
    g = src.graph
    m = g.n_elements
    name = np.asarray(labels, dtype=np.int64)[src.first_rows(np.arange(m))]
    names, dense = np.unique(name, return_inverse=True)
    piece = label_components(g, dense)
    n_pieces = int(piece.max()) + 1
    piece_name = np.empty(n_pieces, dtype=np.int64)
    piece_name[piece] = name
    if n_pieces == names.size or not owned.size:
        return None
    area = np.bincount(piece, weights=g.sizes, minlength=n_pieces)
    mine = np.isin(piece_name, owned)
    stray = mine.copy()
    main = {}
    at = src.to_rows(np.arange(m))[np.asarray(owned_rows, dtype=np.int64)]
    for nm, e in zip(owned.tolist(), at.tolist()):
        if e >= 0 and name[e] == nm:
            main[nm] = int(piece[e])
    for p in np.lexsort((np.arange(n_pieces), -area)).tolist():  # else the largest
        if mine[p]:
            main.setdefault(int(piece_name[p]), p)
    stray[list(main.values())] = False
    if not stray.any():
        return None
    pi, pj = piece[g.pairs[:, 0]], piece[g.pairs[:, 1]]
    cross = (pi != pj) & (stray[pi] | stray[pj])
    a = np.concatenate([pi[cross], pj[cross]])
    b = np.concatenate([pj[cross], pi[cross]])
    length = np.concatenate([g.lengths[cross], g.lengths[cross]])
    final = piece_name.copy()
    waiting = [int(p) for p in np.flatnonzero(stray)[np.argsort(area[stray], kind="stable")]]
    while waiting:
        left = []
        for p in waiting:
            nb, w = b[a == p], length[a == p]
            ok = ~stray[nb]
            if not ok.any():
                left.append(p)
                continue
            border = np.bincount(nb[ok], weights=w[ok], minlength=n_pieces)
            final[p] = final[int(np.argmax(border))]
            stray[p] = False
        if len(left) == len(waiting):  # isolated: keeps its name
            break
        waiting = left
    out = src.to_rows(final[piece])
    return np.where(out >= 0, out, -1).astype(np.int64)


def halo_distance(halo: float, window: float, r: float) -> float:
    """The halo's width in mesh units (``halo * window * r``).

    Raises
    ------
    ParameterError
        If ``halo < 1`` (the issue's floor: a tile must see at least one
        expansion's reach) or not finite.
    """
    if isinstance(halo, bool) or not isinstance(halo, (int, float)) or not math.isfinite(halo) \
            or halo < 1.0:
        raise ParameterError(f"halo must be a number >= 1 (in units of window * r), got {halo!r}")
    return float(halo) * window * r
