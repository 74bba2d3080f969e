"""The stages of one run of the method, each entered once, in the paper's order.

:func:`superfacets.method.pipeline.pipeline` runs them (its notes list them); tiled runs
(:mod:`superfacets.scale.tiles.phases`) call the same ones. Each stage takes what the one before
hands it: the element graph, the run's :class:`Rules` (every automatic rule
resolved once), the weights, the centers, the labels. :class:`Hooks` hold what runs
around them: timings, the progress bar, the release of memory.
"""

from __future__ import annotations

import zlib
from dataclasses import dataclass, replace

import numpy as np

from ..elements.builders import ElementInput, check_count, elements_of, prepared
from ..elements.density import adapted_graph, density_for
from ..elements.features import colors_or_features, features_of, per_element
from ..elements.graph import ElementGraph, cached_on
from ..elements.kinds import ElementKind, kind_of
from ..elements.vertices import symmetric_terms
from ..errors import ParameterError
from ..inputs.cloud import check_weighable, up_weighted
from .classify import make_classifier
from .coarse_to_fine import COARSENING_READS, coarsening_for, start_centers
from .expansion import Workspaces
from .params import (
    DEFAULT_CENTER_TOL,
    DEFAULTS,
    SegmentParams,
    assignment_of,
    better_method,
    superfacet_size,
)
from .passes import Iteration, iterate
from .rules import fine_count, merge_from_of, scene_default_of, up_weight_of
from .splitmerge import FAST_ROUNDS, ROUNDS, swap_and_iterate
from .weights import (
    HeldWeights,
    convex_scaled,
    csr_point_weights,
    csr_weights,
    edge_weights,
    feature_scale,
    weight_dtype,
)

__all__ = ["Rules", "build_graph", "resolve_features", "resolve_rules", "weigh",
           "initialize", "iterate_passes", "stage_reads"]

_D = DEFAULTS



@dataclass(frozen=True)
class Rules:
    """The automatic rules of one run, resolved once (:func:`resolve_rules`).

    Attributes
    ----------
    params : SegmentParams
        The run's parameters with ``density`` and ``assignment`` resolved.
    kind : ElementKind
        The row of the table of kinds (:mod:`superfacets.elements.kinds`).
    k : int or None
        Initial centers (None: flood and grid with a radius decide).
    r : float
        Superfacet radius in mesh units (paper section 3.1).
    cleanup, split_merge : bool
        The stages on or off.
    center_tol : float
        A center moving less than ``center_tol * r`` stays.
    coarsen : int
        Elements per cluster of the coarse run (1: none).
    target : int or None
        The count the run returns: ``k``, or the count asked for where the run
        segments ``merge_from`` times more and merges (:mod:`superfacets.method.merges`).
    feature_floor : float
        Feature differences up to it cost nothing (:func:`resolve_features`).

    Examples
    --------
    >>> rules = passes_example().rules  # (an icosphere's run: faces)
    >>> rules.k, rules.kind.name, rules.cleanup, rules.params.assignment
    (12, 'faces', True, 'bounded')
    """

    params: SegmentParams
    kind: ElementKind
    k: int | None
    r: float
    cleanup: bool
    split_merge: bool
    center_tol: float
    coarsen: int
    target: int | None = None
    feature_floor: float = 0.0

    @property
    def fast(self) -> bool:
        """Swaps early and few passes after them (split-and-merge with ``tol > 0``)."""
        return self.split_merge and self.params.tol > 0

    @property
    def window_r2(self) -> float:
        """The squared reach of an expansion, ``(window r)^2`` (section 3.1)."""
        return (self.params.window * self.r) ** 2


_UNSET = object()


def check_stage(name: str, *, graph=_UNSET, rules=_UNSET, params=_UNSET) -> None:
    """A TypeError that says what a stage takes, where it is given something else: the
    run's element graph (:func:`build_graph`), its rules (:func:`resolve_rules`), its
    parameters (:func:`superfacets.method.params.resolve`)."""
    for given, want, what in ((graph, ElementGraph, "the run's element graph (build_graph)"),
                              (rules, Rules, "the run's rules (resolve_rules)"),
                              (params, SegmentParams, "the run's parameters (resolve)")):
        if given is not _UNSET and not isinstance(given, want):
            raise TypeError(f"{name} takes {what}, got {type(given).__name__}")


def stage_reads(rules: Rules, initial=None) -> tuple[tuple[str, frozenset], ...]:
    """What each stage after the graph's build reads of the fields the graph can
    forget and make again (its :attr:`~superfacets.elements.graph.ElementGraph.rebuild`
    fields and its cached :attr:`~superfacets.elements.graph.ElementGraph.terms`), in the
    run's order (Algorithm 1).

    Besides these, every stage reads the CSR layout, the positions and the sizes, which
    are never forgotten. The passes read nothing more: :meth:`superfacets.method.pipeline.
    Hooks.before` (the one place that forgets) lets go, on a large graph, of what no
    stage before the passes still reads, and the stages after them make again what they
    read (the passes are a run's memory peak).

    Parameters
    ----------
    rules : Rules
    initial : (c,) int ndarray, optional
        Given centers (no initialization, so no coarsening).

    Returns
    -------
    tuple of (str, frozenset of str)
        ``(stage, fields)`` in the run's order: ``"pair weights"`` (eqs. 1-3 per
        adjacency), ``"weight layout"`` (per CSR entry, and the swap energies'),
        ``"coarsening"`` (where the rules coarsen), ``"passes"``, and ``"clean-up"``
        (its bands) and ``"cuts"`` (where it runs).

    Raises
    ------
    TypeError
        If an argument is not what the earlier stage gives (a word, an array).
    AttributeError
        Never for rules from :func:`resolve_rules`.

    Examples
    --------
    >>> ball = trimesh.creation.icosphere(subdivisions=3)
    >>> _, graph, p = build_graph(ball, resolve(n_segments=12))
    >>> [(name, sorted(fields)) for name, fields in stage_reads(resolve_rules(graph, p))][1:]
    ... # doctest: +NORMALIZE_WHITESPACE
    [('weight layout', ['dual_edge', 'lengths', 'spans', 'terms']), ('passes', []),
     ('clean-up', ['dual_edge', 'lengths', 'terms']), ('cuts', [])]
    """
    check_stage("stage_reads", rules=rules)
    plan = [("pair weights", {"normals", "pairs", "lengths", "spans", "border_shares",
                              "terms"}),
            ("weight layout", {"dual_edge"} | ({"terms", "spans", "lengths"}
                                               if rules.split_merge else set()))]
    if rules.coarsen > 1 and initial is None:
        plan.append(("coarsening", set(COARSENING_READS)))
    plan.append(("passes", set()))
    if rules.cleanup:  # (its bands read these; its cuts, after them, none)
        plan += [("clean-up", {"terms", "dual_edge", "lengths"}), ("cuts", set())]
    return tuple((name, frozenset(fields)) for name, fields in plan)


def build_graph(obj, p: SegmentParams, features=None
                ) -> tuple[ElementInput, object, SegmentParams]:
    """Stage 1: the input's element graph, with content-sensitive sizes where asked.

    ``n_segments`` is checked against the input's elements, and ``features`` (with
    ``beta > 0``) against its rows, before the graph is built (the memory peak of a
    run). ``density=None`` is resolved here, from the
    graph (:func:`superfacets.elements.density.density_for`); with ``density`` or
    ``roughness`` above 0 the returned graph's sizes are stretched
    (:func:`superfacets.elements.density.adapted_graph`; the cached graph is not changed).

    Returns
    -------
    source : ElementInput
    graph : ElementGraph
        The graph the method runs on.
    params : SegmentParams
        ``p`` with ``density`` resolved.

    Parameters
    ----------
    obj : Mesh, PointCloud, TetMesh, or what they are made from
    p : SegmentParams
        From :func:`superfacets.method.params.resolve`.
    features : (N, d) float ndarray, optional
        With ``beta > 0``: one row per input row (checked here).

    Raises
    ------
    TypeError
        If an argument is not what the earlier stage gives (a word, an array).
    ParameterError
        If ``n_segments`` exceeds the elements, or the features do not fit.
    InvalidMeshError, InvalidCloudError, MemoryLimitError
        As the input's validation; a run that would not fit in memory.

    Examples
    --------
    >>> cloud = PointCloud(np.random.default_rng(0).random((500, 3)))
    >>> src, graph, p = build_graph(cloud, resolve(n_segments=12))
    >>> graph.kind, graph.n_elements, p.density    # (density: an even cloud's, 0)
    ('points', 500, 0.0)
    """
    check_stage("build_graph", params=p)
    kind, data = prepared(obj, p.elements, n_segments=p.n_segments)
    p, data = _weighed(p, kind, data)
    if p.beta is not None and p.beta > 0:
        _check_features(kind, data, features)
    scene = getattr(data, "up", None) is not None
    p = replace(p, step_weight=scene_default_of(p, "step_weight", kind, scene))
    source = elements_of(data, kind, n_neighbors=p.n_neighbors,
                         neighbor_radius=p.neighbor_radius, step_weight=p.step_weight)
    graph = source.graph
    if p.radius is None and p.n_segments is not None:  # (points: distinct ones, known now)
        check_count(p.n_segments, graph.n_elements, source.n_rows, kind)
    if p.density is None:  # automatic: superpoints follow a scan's uneven density
        p = replace(p, density=density_for(graph, p.paper))
    if p.density > 0 or p.roughness > 0:  # content-sensitive sizes (not in the paper)
        graph = adapted_graph(graph, p.density, p.roughness)
    return source, graph, p


def _weighed(p, kind: str, data) -> tuple:
    """``p`` with ``up_weight`` resolved (:func:`~superfacets.method.rules.up_weight_of`)
    and the cloud the method reads: ``data``, or (not in the paper) its copy with the up
    coordinate weighed. The weight read off a scene and the weighed copy are kept with
    ``data`` (:func:`~superfacets.elements.graph.cached_on`), so that runs of one cloud at
    several counts (a count's search, a hierarchy) build the weighed copy's graph once,
    as they build an unweighed cloud's."""
    up = getattr(data, "up", None)
    weight = up_weight_of(p, kind, up, getattr(data, "points", None), owner=data)
    p = replace(p, up_weight=weight)
    if weight == 1:
        return p, data
    check_weighable(kind_of(kind).cloud, kind, up)

    def weigh():
        weighted = up_weighted(data, weight)
        weighted.__dict__["unweighted"] = data  # (a result's graphs read the data's units)
        return weighted

    return p, cached_on(data, f"up_weighted {weight!r}", weigh)


def _check_features(kind: str, data, features) -> None:
    """``beta > 0``: features of one row per input row, or colours (materials) to use."""

    if features is not None:
        n = kind_of(kind).n_rows(data)
        f = np.shape(features)
        if len(f) not in (1, 2) or f[0] != n:
            raise ParameterError(f"features must have one row per input row ({n}), "
                                 f"got shape {f}")
        return
    if all(getattr(data, name, None) is None for name in ("colors", "face_colors",
                                                           "materials")):
        raise ParameterError("beta > 0 needs features: pass features=(one row per "
                             f"{kind_of(kind).singular}), or an input with colours (PLY, PCD "
                             "or LAS points with RGB, a mesh with vertex or face colours) "
                             "or materials (a tetrahedral mesh)")


def resolve_features(source: ElementInput, graph, p: SegmentParams, features=None,
                     floor: float | None = None) -> tuple[SegmentParams, np.ndarray | None, float]:
    """Stage 2a (not in the paper): the feature (colour) term of the weights.

    ``beta=None`` (the default) reads it from the data where the input has colours (a
    cloud's or a mesh's) or ``features`` are given: differences up to the features'
    noise between neighbours cost nothing, and the rest weighs, on average, as much as
    distance and angle together (:func:`superfacets.method.weights.feature_scale`); 0
    where there are none. A ``beta`` given keeps its value, with the same floor.

    Parameters
    ----------
    source : ElementInput
    graph : ElementGraph
        The graph the run weighs (:func:`build_graph`).
    p : SegmentParams
    features : (N, d) float ndarray, optional
        One row per input row (default: the input's colours).
    floor : float, optional
        With ``p.beta`` a number: the floor, not read from this input (a tiled run's
        tiles take the one read once over all of them, so that they weigh a border alike).

    Returns
    -------
    params : SegmentParams
        ``p`` with ``beta`` a number.
    features : (n, d) float64 ndarray or None
        One row per element, where ``beta > 0``.
    floor : float

    Raises
    ------
    TypeError
        If an argument is not what the earlier stage gives (a word, an array).
    ParameterError
        If ``beta > 0`` and the input has no features, or they do not fit.

    Examples
    --------
    >>> ball = trimesh.creation.icosphere(subdivisions=3)
    >>> src, graph, p = build_graph(ball, resolve(n_segments=12))
    >>> resolve_features(src, graph, p)[0].beta  # no colours: no colour term
    0.0
    >>> rgb = np.where((ball.triangles_center[:, 2] > 0)[:, None], [1.0, 0, 0], [0, 0, 1])
    >>> p, feats, floor = resolve_features(src, graph, p, rgb)
    >>> p.beta > 0, feats.shape, floor
    (True, (1280, 3), 0.0)
    """
    check_stage("resolve_features", graph=graph, params=p)

    if p.beta is not None and p.beta <= 0:
        return p, None, 0.0
    given = colors_or_features(source, features) if p.beta is None else None
    if p.beta is None and given is None:
        return replace(p, beta=0.0), None, 0.0
    feats = per_element(source, given) if given is not None else features_of(source, features)
    if p.beta is None and not np.isfinite(feats).all():  # (asked for none: not an error)
        import warnings

        warnings.warn("the colour term is off: the input's colours (or features) are not all "
                      "finite numbers", RuntimeWarning, stacklevel=3)
        return replace(p, beta=0.0), None, 0.0
    if floor is not None and p.beta is not None:
        return p, (feats if p.beta > 0 else None), float(floor)
    alpha = p.alpha if p.weighting == "paper" else _D.alpha
    beta, floor = feature_scale(graph, feats, alpha=alpha, eta_convex=p.eta_convex)
    if p.beta is not None:
        beta = p.beta
    return replace(p, beta=beta), (feats if beta > 0 else None), floor


def resolve_rules(graph, p: SegmentParams, *, n_centers: int | None = None,
                  r: float | None = None, feature_floor: float = 0.0,
                  scene: bool = False) -> Rules:
    """Stage 2: every automatic rule of the run, once, from the table of kinds.

    ``k`` and ``r`` (paper section 3.1: ``r = sqrt(A / (k pi))``, or ``radius`` times
    the diagonal), clean-up and split-and-merge
    (:func:`superfacets.method.params.better_method`), the classification
    (:func:`superfacets.method.params.assignment_of`), the center tolerance (0.05 of ``r``
    with ``tol > 0``), the coarsening (:func:`superfacets.method.coarse_to_fine.coarsening_for`)
    and ``merge_from`` (:func:`superfacets.method.rules.merge_from_of`: where it is above 1,
    ``k`` is :func:`~superfacets.method.rules.fine_count`: ``merge_from`` times the count
    asked for, ``target``, at least one superpoint per
    :data:`~superfacets.method.rules.FINE_ELEMENTS` elements, at most one per
    :data:`~superfacets.method.rules.MIN_FINE_ELEMENTS`, or where that is under twice the
    count, twice it, at most one per
    :data:`~superfacets.method.rules.FEWEST_FINE_ELEMENTS`).

    Parameters
    ----------
    graph : ElementGraph
    p : SegmentParams
        With ``density`` resolved (:func:`build_graph`).
    n_centers : int, optional
        Initial centers instead of the number the radius gives (a tile).
    r : float, optional
        The radius in mesh units, instead of the one ``p`` gives (a tile of a
        tiled run takes the whole run's).
    feature_floor : float, default 0
        From :func:`resolve_features` (a ``beta`` it has not resolved, None, is 0).
    scene : bool, default False
        The input has an up direction (``PointCloud.up``): a scene's ``merge_from``
        (:func:`~superfacets.method.rules.merge_from_of`).

    Returns
    -------
    Rules

    Raises
    ------
    TypeError
        If an argument is not what the earlier stage gives (a word, an array).
    ParameterError
        If ``n_segments`` exceeds the elements or the radius is too small
        (:func:`superfacets.method.params.superfacet_size`).

    Examples
    --------
    >>> ball = trimesh.creation.icosphere(subdivisions=3)
    >>> src, graph, p = build_graph(ball, resolve(n_segments=12))
    >>> rules = resolve_rules(graph, p)
    >>> rules.k, round(rules.r, 4), rules.center_tol, rules.coarsen
    (12, 0.576, 0.05, 1)
    """
    check_stage("resolve_rules", graph=graph, params=p)
    if p.beta is None:
        p = replace(p, beta=0.0)
    k, radius = superfacet_size(p, graph.area, graph.diagonal, graph.n_elements, graph.kind)
    if n_centers is not None:
        k = int(min(max(n_centers, 1), graph.n_elements))
    target = k
    merge_from = merge_from_of(p, graph.kind, tiled=n_centers is not None or r is not None,
                               scene=scene)
    p = replace(p, merge_from=merge_from,
                max_size_ratio=scene_default_of(p, "max_size_ratio", graph.kind, scene))
    if merge_from > 1 and k is not None:  # many superpoints first, merged to k at the end
        fine = fine_count(k, merge_from, graph.n_elements)
        k, radius = superfacet_size(replace(p, n_segments=fine, radius=None), graph.area,
                                    graph.diagonal, graph.n_elements, graph.kind)
    radius = radius if r is None else r
    cleanup, split_merge = better_method(p, graph.kind)
    p = replace(p, assignment=assignment_of(p, graph.kind))
    center_tol = p.center_tol if p.center_tol is not None else (
        DEFAULT_CENTER_TOL if p.tol > 0 else 0.0)
    return Rules(params=p, kind=kind_of(graph.kind), k=k, r=radius, cleanup=cleanup,
                 split_merge=split_merge, center_tol=center_tol,
                 coarsen=coarsening_for(graph, p, k, radius), target=target,
                 feature_floor=feature_floor)


def weigh(graph, rules: Rules, features=None, hooks=None
          ) -> tuple[np.ndarray, np.ndarray | None]:
    """Stage 3: the weight of each adjacency, per CSR entry (paper eqs. 1-3, or
    Shlafman's eq. 6; with ``beta``, the feature term), and the swap energies'
    weights where split-and-merge runs (convex folds scaled by the kind's
    ``swap_eta_convex``).

    With the clean-up the adjacency terms are cached on the graph first (it reads
    them again). Once the weight of each pair is made, ``hooks.before("weight
    layout")`` forgets what the later stages do not read (on a large graph: the pairs,
    before the weights are laid out per CSR entry, this stage's memory peak;
    :func:`stage_reads`).

    Returns
    -------
    weights : (2 e,) float64 or float32 ndarray
        One per CSR entry; float32 on the kinds the table marks ``single_weights``
        (points), unless ``paper`` (:func:`~superfacets.method.weights.weight_dtype`).
    swap_weights : (2 e,) ndarray of the same dtype, or None

    Parameters
    ----------
    graph : ElementGraph
    rules : Rules
    features : (n, d) float ndarray, optional
        Per-element features, with ``beta > 0``.
    hooks : Hooks, optional
        The run's :class:`~superfacets.method.pipeline.Hooks` (None: nothing is
        forgotten).

    Raises
    ------
    TypeError
        If an argument is not what the earlier stage gives (a word, an array).
    ParameterError
        If the features do not fit the graph.

    Examples
    --------
    >>> s = passes_example()  # an icosphere's run up to its passes
    >>> w, swap_w = weigh(s.graph, s.rules)
    >>> w.shape == (2 * s.graph.n_edges,), swap_w is not None
    (True, True)
    """
    check_stage("weigh", graph=graph, rules=rules)
    kept = graph.__dict__.get("weights_kept")  # (a tiled run's held graph: made once)
    key = None if kept is None else _weights_key(graph, rules, features)
    p = rules.params
    if key is not None and key in kept:
        w, swap_w = kept[key]
        if rules.split_merge and swap_w is None:  # (made once too)
            swap_w = _swap_weights(graph, w, rules)
            swap_w.flags.writeable = False
            kept[key] = (w, swap_w)
        return w, swap_w if rules.split_merge else None
    if rules.cleanup:
        graph.terms  # noqa: B018 (kept for the clean-up; else computed chunk by chunk)
    dtype = weight_dtype(rules.kind, p.paper)
    if _per_entry(graph, rules):
        # points, vertices: from the CSR layout, positions and normals (the same values)
        w = csr_point_weights(graph, alpha=p.alpha, eta_convex=p.eta_convex, dtype=dtype,
                              features=features, beta=p.beta, floor=rules.feature_floor,
                              step=p.step_weight or 1.0)
    else:
        w_pairs = edge_weights(graph, p.weighting, alpha=p.alpha, eta_convex=p.eta_convex,
                               features=features, beta=p.beta, floor=rules.feature_floor,
                               dtype=dtype)
        if hooks is not None:
            hooks.before("weight layout")
        w = csr_weights(graph, w_pairs, dtype)
        del w_pairs  # the coarsening reads the same values from ``w``
    swap_w = _swap_weights(graph, w, rules) if rules.split_merge else None
    if key is not None:  # (read-only: every phase that reads them gets these arrays)
        for a in (w, swap_w):
            if a is not None:
                a.flags.writeable = False
        kept[key] = (w, swap_w)
    return w, swap_w


def _swap_weights(graph, w: np.ndarray, rules: Rules) -> np.ndarray:
    """The swap energies' weights from the run's (on faces: convex folds count half)."""
    p = rules.params
    return convex_scaled(graph, w, alpha=p.alpha, eta_convex=p.eta_convex,
                         factor=rules.kind.swap_eta_convex, weighting=p.weighting
                         ).astype(w.dtype, copy=False)


def _weights_key(graph, rules: Rules, features) -> tuple:
    """What :func:`weigh` reads besides the graph: the key of the weights a held graph
    keeps (``graph.weights_kept``)."""
    p = rules.params
    feats = None
    if features is not None:
        f = np.ascontiguousarray(features)
        feats = (f.dtype.str, f.shape, zlib.crc32(f.view(np.uint8).reshape(-1)))
    return (p.alpha, p.eta_convex, p.beta, p.weighting, p.paper, rules.feature_floor,
            rules.kind.name, _per_entry(graph, rules), feats, p.step_weight)


def held_weights(graph, rules: Rules, w: np.ndarray, features=None, initial=None
                 ) -> HeldWeights:
    """Stage 3's weights as the start holds them: let go by the coarse start where they
    are made again cheaply (the compiled weights of points and vertices, from the CSR
    layout, positions and normals, which the passes keep) and the start runs coarse; the
    passes then read them made again, the same values.

    Returns
    -------
    HeldWeights

    Examples
    --------
    >>> s = passes_example()
    >>> held = held_weights(s.graph, s.rules, s.w)
    >>> held.let_go(); held.remade, held.get().dtype.name  # (faces: never let go)
    (0, 'float32')
    """
    check_stage("held_weights", graph=graph, rules=rules)
    if not _per_entry(graph, rules) or rules.coarsen <= 1 or initial is not None:
        return HeldWeights(w)
    return HeldWeights(w, remake=lambda: weigh(graph, rules, features)[0])


def _per_entry(graph, rules: Rules) -> bool:
    """Whether :func:`weigh` makes the weights per CSR entry in one compiled pass (points
    and vertices with the paper's weighting, no clean-up, no split-and-merge)."""
    p = rules.params
    return (graph.terms_of is symmetric_terms and p.weighting == "paper"
            and not rules.cleanup and not rules.split_merge)


def initialize(graph, w: np.ndarray, rules: Rules, hooks,
               initial: np.ndarray | None = None) -> tuple[np.ndarray, int]:
    """Stage 4: the first centers (paper section 3.1, step 1): farthest point,
    flood or grid, after a coarse run on clusters where the rules say
    (:func:`superfacets.method.coarse_to_fine.start_centers`); or ``initial``.

    Returns
    -------
    centers : (c,) int64 ndarray
        Elements.
    coarsen : int
        The coarsening used (1: none).

    Parameters
    ----------
    graph : ElementGraph
    w : (2 e,) float64 ndarray
        The CSR weights (:func:`weigh`).
    rules : Rules
    hooks : Hooks
    initial : (c,) int ndarray, optional
        Elements to start from instead.

    Raises
    ------
    TypeError
        If an argument is not what the earlier stage gives (a word, an array).
    ParameterError
        Never for rules from :func:`resolve_rules`.

    Examples
    --------
    >>> s = passes_example()
    >>> init, coarsen = initialize(s.graph, s.w, s.rules, s.hooks)
    >>> init.shape, coarsen
    ((12,), 1)
    """
    check_stage("initialize", graph=graph, rules=rules)
    if initial is not None:
        return np.asarray(initial, dtype=np.int64), 1
    if rules.coarsen > 1:
        hooks.before("coarsening")
    return start_centers(graph, w, rules.params, rules.k, rules.r, rules.coarsen,
                         rules.center_tol, hooks.timings, hooks.describe,
                         on_coarsened=lambda: hooks.before("passes"))


def iterate_passes(graph, w: np.ndarray, swap_w, init: np.ndarray, rules: Rules,
                   hooks, *, replay: bool = True, jump_cycles: bool = True,
                   order: np.ndarray | None = None, fixed: np.ndarray | None = None,
                   keep_classifier: bool = False) -> Iteration:
    """Stage 5: passes of (classify, update) until no center moves, ``tol`` or
    ``max_iter`` (paper section 3.1, steps 2-3); then, with split-and-merge, the
    K-preserving swaps and the passes again (with ``tol > 0``: the swaps once a pass
    changes at most ``START_TOL`` of the area, one round, then at most the kind's
    ``passes_after`` passes).

    Returns
    -------
    Iteration

    Parameters
    ----------
    graph : ElementGraph
    w, swap_w : float64 ndarray
        The weights and the swap energies' weights (:func:`weigh`).
    init : (c,) int64 ndarray
        The first centers (:func:`initialize`).
    rules : Rules
    hooks : Hooks
    replay, jump_cycles : bool
        As :func:`superfacets.method.pipeline.pipeline` (the same labels either way).
    order : (n,) int64 ndarray, optional
        The passes' centers listed by this key of their elements
        (:func:`superfacets.method.passes.iterate`); not with split-and-merge.
    fixed : (n,) bool ndarray, optional
        Elements whose centers stay and take no part in a swap
        (:func:`superfacets.method.passes.iterate`).
    keep_classifier : bool, default False
        Return the classifier with the iteration (``Iteration.classifier``): a bounded
        one keeps its last pass's expansions (about 60 bytes per element), which a tile's
        labels phase replays (:func:`superfacets.scale.tiles.phases.tile_labels`).

    Raises
    ------
    TypeError
        If an argument is not what the earlier stage gives (a word, an array).
    ParameterError
        Never for rules from :func:`resolve_rules`.

    Examples
    --------
    >>> s = passes_example()
    >>> it = iterate_passes(s.graph, s.w, s.swap_w, s.init, s.rules, s.hooks)
    >>> it.label.shape, it.n_iter >= 1
    ((1280,), True)
    """
    check_stage("iterate_passes", graph=graph, rules=rules)
    p = rules.params
    spaces = Workspaces(graph.n_elements, w, p.n_threads)
    centers = np.empty(graph.n_elements, dtype=np.int64)
    centers[:init.shape[0]] = init
    sizes = np.ascontiguousarray(graph.sizes)
    positions = np.ascontiguousarray(graph.positions)
    min_move = rules.center_tol * rules.r
    settle = rules.kind.settle_cycles and not p.paper
    try:
        classifier = make_classifier(p.assignment, graph, w, rules.window_r2, spaces,
                                     replay=replay)
        if rules.fast:
            from .splitmerge import START_TOL
        it = iterate(classifier, centers, init.shape[0], sizes, positions, p.max_iter,
                     jump_cycles=jump_cycles, tol=max(p.tol, START_TOL) if rules.fast else p.tol,
                     min_move=min_move, bar=hooks.bar, settle=settle,
                     order=None if rules.split_merge else order, fixed=fixed)
        if rules.split_merge:
            hooks.describe("split and merge")
            it, hooks.timings["swaps"] = swap_and_iterate(
                it, graph, w, classifier, centers, sizes, positions, p.max_iter,
                window_r2=rules.window_r2, jump_cycles=jump_cycles, tol=p.tol, settle=settle,
                min_move=min_move, n_threads=spaces.n_threads,
                rounds=FAST_ROUNDS if rules.fast else ROUNDS,
                passes_after=rules.kind.passes_after if rules.fast else None,
                swap_weights=swap_w,
                hold_after=rules.kind.hold_after if rules.fast else 1.0, fixed=fixed)
    finally:
        spaces.close()
    return replace(it, classifier=classifier) if keep_classifier else it

