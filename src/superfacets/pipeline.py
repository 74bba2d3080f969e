"""One run of the superfacet method, as named stages (paper section 3; ``docs/method.md``).

:func:`pipeline` takes validated parameters (:func:`superfacets.params.resolve`;
the public functions of :mod:`superfacets.segmentation` call it) and runs, each
stage entered once and in the paper's order (Algorithm 1):

1. :func:`build_graph`: the element graph (``n_segments`` checked against the
   input's elements first); with ``density`` (resolved here: it reads the graph)
   or ``roughness``, its sizes stretched (:mod:`superfacets.adaptive`);
2. :func:`resolve_rules`: the automatic rules, once: ``k`` and the radius ``r``
   (section 3.1), clean-up and split-and-merge, the classification, the center
   tolerance and the coarsening, from the table of kinds
   (:mod:`superfacets.elements.kinds`);
3. :func:`weigh`: the adjacency weights (eqs. 1-3, or Shlafman's eq. 6), and the
   swap energies' weights;
4. :func:`initialize`: the first centers (farthest point, flood or grid, after a
   coarse run on clusters where it pays: :mod:`superfacets.multilevel`);
5. :func:`iterate_passes`: passes of (classify, update) until no center moves,
   ``tol`` or ``max_iter`` (:mod:`superfacets.passes`, with a strategy of
   :mod:`superfacets.classify`); with split-and-merge, the K-preserving swaps and
   the passes again (:mod:`superfacets.splitmerge`);
6. :func:`finish`: empty superfacets dropped, labels made dense, stray pieces
   merged (connectivity);
7. :func:`clean_up`: the boundaries re-placed (:mod:`superfacets.cleanup`);
8. :func:`merge_small`: superfacets of fewer than ``min_elements`` merged.

Timings, the progress bar and the release of memory are hooks around the stages
(:class:`_Hooks`), not inside them. Tiled runs (:mod:`superfacets.tiling`) call
the same stages.
"""

from __future__ import annotations

import time
from contextlib import contextmanager
from dataclasses import dataclass, field, replace

import numpy as np

from .adaptive import adapted_graph, density_for
from .classify import make_classifier
from .cleanup import clean_boundaries
from .connectivity import enforce_connectivity as _enforce_connectivity
from .expansion import Workspaces
from .labels import relabel_dense
from .elements.inputs import ElementInput, elements_of
from .elements.kinds import ElementKind, kind_of
from .multilevel import coarsening_for, start_centers
from .params import (DEFAULT_CENTER_TOL, DEFAULTS, SegmentParams, assignment_of, better_method,
                     superfacet_size)
from .passes import Iteration, final_centers, iterate
from .weights import csr_weights, edge_weights

__all__ = ["pipeline", "SegmentationResult", "Rules", "build_graph", "resolve_rules", "weigh",
           "initialize", "iterate_passes", "finish", "clean_up", "merge_small", "features_of"]

_D = DEFAULTS

#: Elements from which a run makes its graph forget, during the passes, the arrays
#: they do not read (:meth:`ElementGraph.release`: about 60 bytes per face of the
#: peak). Below it, rebuilding them after costs more than the memory is worth.
_RELEASE_MIN = 1 << 18


@dataclass(frozen=True)
class SegmentationResult:
    """Labels and details of one run of :func:`segment`.

    Attributes
    ----------
    labels : (m,) int64 ndarray
        Superfacet of each face, dense ``0..K-1``.
    centers : (K,) int64 ndarray
        Center face of each superfacet (the center of the last
        classification; for a superfacet that lost it to the connectivity
        step, its face nearest the area-weighted mean of its centroids).
    n_iter : int
        Number of classification passes run.
    converged : bool
        True if the run stopped by its rule: the last center update moved no
        center, a pass changed at most ``tol`` of the area, or the passes
        after the split-and-merge swaps were done; False if ``max_iter``
        stopped it.
    mesh_radius : float
        Superfacet radius ``r`` used, in the input's units (the ``radius``
        parameter, ``params['radius']``, is a fraction of the bounding-box
        diagonal). ``radius`` is its old name (deprecated; one release).
    n_orphan_seeds : int
        Centers created on orphan faces over the whole run.
    timings : dict of str to float
        Seconds per stage: ``graph`` (face graph and per-face geometry,
        zero when already cached on the mesh), ``weights``, ``init``,
        ``iterations``, ``connectivity``, ``cleanup`` (with ``cleanup=True``),
        ``total``; and, not times,
        ``expansions`` (Dijkstra expansions run), ``passes``
        (classifications actually run: fewer than ``n_iter`` when a cycle
        was skipped) and ``cycle_period`` (0, or the period of the cycle of
        center sets that was detected).
    params : dict
        The parameters of the run, resolved (``n_segments``, ``radius``,
        ``init``, ...).
    """

    labels: np.ndarray
    centers: np.ndarray
    n_iter: int
    converged: bool
    mesh_radius: float
    n_orphan_seeds: int
    timings: dict = field(default_factory=dict)
    params: dict = field(default_factory=dict)
    #: The input's element graph and the label of each element (not of each row),
    #: for :meth:`graph` and :meth:`hierarchy`.
    elements: object = field(default=None, repr=False, compare=False)
    element_labels: np.ndarray | None = field(default=None, repr=False, compare=False)

    @property
    def n_segments(self) -> int:
        """Number of superfacets ``K`` produced."""
        return int(self.centers.shape[0])

    @property
    def radius(self) -> float:
        """The old name of :attr:`mesh_radius` (deprecated; one release)."""
        return _deprecated_radius(self)

    def graph(self, features=None):
        """The superfacet (superpoint) adjacency graph of this result.

        Parameters
        ----------
        features : (N, d) float ndarray, optional
            One feature per input row (face, vertex or point, e.g. RGB
            colour); ``feature`` of the graph is its area-weighted mean per
            superfacet (rows that are not elements are left out). Default:
            the input's colours if it has any (a cloud read with RGB), else none.

        Returns
        -------
        SuperfacetGraph
            ``edge_index`` (2, E), ``border_length``, ``mean_angle``,
            ``concave``, ``area``, ``centroid``, ``normal``, ``feature``;
            ``to_scipy()``, ``to_networkx()``, ``save(path)``
            (:mod:`superfacets.adjacency`).

        Raises
        ------
        ParameterError
            If ``features`` does not have one finite row per input row.

        Examples
        --------
        >>> import trimesh
        >>> from superfacets import segment
        >>> r = segment(trimesh.creation.icosphere(subdivisions=3), 12)
        >>> g = r.graph()
        >>> g.n_segments, g.edge_index.shape[0], bool((g.border_length > 0).all())
        (12, 2, True)
        """
        from .adjacency import superfacet_graph

        src = self._source()
        if features is None:
            features = src.colors()
        return superfacet_graph(src.graph, self.element_labels, _per_element(src, features))

    def hierarchy(self, levels, *, beta: float = 0.0, features=None, cost: str = "ward",
                  extent_weight: float | None = None, compactness: float | None = None):
        """Nested coarser levels of these superfacets, each segment connected
        (:func:`superfacets.hierarchy.hierarchy`, with this run's ``alpha`` and
        ``eta_convex``).

        Parameters
        ----------
        levels : int or sequence of int
            Numbers of segments of the levels, each at most ``K``.
        beta : float, default 0
            Weight of the feature difference (needs ``features``).
        features : (N, d) float ndarray, optional
            One feature per input row, as :meth:`graph`.
        cost : {'ward', 'planarity'}, default 'ward'
            Compact segments, or flat regions merged first
            (:func:`superfacets.hierarchy.hierarchy`; on a point cloud each point
            weighs one, :func:`~superfacets.hierarchy.planarity_graph`).
        extent_weight : float, optional
            With ``cost='planarity'``, the weight of the segments' extent
            (:func:`superfacets.hierarchy.hierarchy`). Default: left to the
            method, :func:`~superfacets.hierarchy.level_extent_weight` (0.01 on
            a scan of uneven density, else 0).
        compactness : float, optional
            The old name of ``extent_weight`` (deprecated; one release).

        Returns
        -------
        Hierarchy
            ``.parents[i]``: the parent of each segment of the level below;
            ``.labels(i, result.labels)``: one label per input row at level ``i``.

        Raises
        ------
        ParameterError
            If a level is out of range.

        Examples
        --------
        >>> import trimesh
        >>> from superfacets import segment
        >>> r = segment(trimesh.creation.icosphere(subdivisions=4), 40)
        >>> h = r.hierarchy([10, 3])
        >>> [int(h.labels(i, r.labels).max()) + 1 for i in range(2)]
        [10, 3]
        """
        from .hierarchy import hierarchy, level_extent_weight, planarity_graph
        from .params import renamed

        extent_weight = renamed(extent_weight, compactness, "extent_weight", "compactness")
        if cost == "planarity":
            src = self._source()
            graph = planarity_graph(src.graph, self.element_labels, _per_element(
                src, src.colors() if features is None else features))
            if extent_weight is None:
                extent_weight = level_extent_weight(src.graph)
        else:
            graph = self.graph(features)
        return hierarchy(graph, levels, alpha=self.params.get("alpha", _D.alpha),
                         eta_convex=self.params.get("eta_convex", _D.eta_convex), beta=beta,
                         cost=cost, extent_weight=extent_weight or 0.0)

    def _source(self):
        if self.elements is None or self.element_labels is None:
            from .errors import ParameterError

            raise ParameterError("this result holds no element graph (made by hand?): use "
                                 "superfacets.adjacency.superfacet_graph(graph, labels)")
        return self.elements


def _deprecated_radius(result) -> float:
    import warnings

    warnings.warn("result.radius is now result.mesh_radius (in the input's units; the "
                  "radius parameter is a fraction of the diagonal); the old name goes in the "
                  "next release", DeprecationWarning, stacklevel=3)
    return result.mesh_radius


def features_of(src, features):
    """The per-element features of a run with ``beta > 0``: ``features`` (one row per
    input row), else the input's colours (or a tetrahedral mesh's materials, one-hot).

    Parameters
    ----------
    src : ElementInput
    features : (N, d) float ndarray or None

    Returns
    -------
    (n, d) float64 ndarray
        One row per element.

    Raises
    ------
    ParameterError
        Without features and without colours, or with one row per input row missing.
    """
    if features is None:
        features = src.colors()
        materials = getattr(src.source, "materials", None)
        if features is None and materials is not None:  # a volume's regions, one-hot
            features = (materials[:, None] == np.unique(materials)[None, :]).astype(float)
        if features is None:
            from .errors import ParameterError

            raise ParameterError("beta > 0 needs features: pass features=(one row per "
                                 f"{src.graph.element}), or an input with colours (PLY, PCD "
                                 "or LAS points with RGB, a mesh with vertex or face colours) "
                                 "or materials (a tetrahedral mesh)")
    return _per_element(src, features)


def _per_element(src, features):
    """Per-row features of an input -> per-element features (the first row of each)."""
    if features is None:
        return None
    from .errors import ParameterError

    f = np.asarray(features, dtype=np.float64)
    f = f.reshape(-1, 1) if f.ndim == 1 else f
    if f.ndim != 2 or f.shape[0] != src.n_rows:
        raise ParameterError(f"features must have one row per input row ({src.n_rows}), "
                             f"got shape {np.shape(features)}")
    rows = src.first_rows(np.arange(src.graph.n_elements))
    return f[rows]


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
    """

    params: SegmentParams
    kind: ElementKind
    k: int | None
    r: float
    cleanup: bool
    split_merge: bool
    center_tol: float
    coarsen: int

    @property
    def fast(self) -> bool:
        """Swaps early and few passes after them (split-and-merge with ``tol > 0``)."""
        return self.split_merge and self.params.tol > 0

    @property
    def window_r2(self) -> float:
        """The squared reach of an expansion, ``(window r)^2`` (section 3.1)."""
        return (self.params.window * self.r) ** 2


def build_graph(obj, p: SegmentParams) -> tuple[ElementInput, object, SegmentParams]:
    """Stage 1: the input's element graph, with content-sensitive sizes where asked.

    ``n_segments`` is checked against the input's elements before the graph is
    built (the memory peak of a run). ``density=None`` is resolved here, from the
    graph (:func:`superfacets.adaptive.density_for`); with ``density`` or
    ``roughness`` above 0 the returned graph's sizes are stretched
    (:func:`superfacets.adaptive.adapted_graph`; the cached graph is not changed).

    Returns
    -------
    source : ElementInput
    graph : ElementGraph
        The graph the method runs on.
    params : SegmentParams
        ``p`` with ``density`` resolved.
    """
    source = elements_of(obj, p.elements, n_neighbors=p.n_neighbors,
                         neighbor_radius=p.neighbor_radius, n_segments=p.n_segments)
    graph = source.graph
    if p.density is None:  # automatic: superpoints follow a scan's uneven density
        p = replace(p, density=density_for(graph, p.paper))
    if p.density > 0 or p.roughness > 0:  # content-sensitive sizes (not in the paper)
        graph = adapted_graph(graph, p.density, p.roughness)
    return source, graph, p


def resolve_rules(graph, p: SegmentParams, *, n_centers: int | None = None,
                  r: float | None = None) -> Rules:
    """Stage 2: every automatic rule of the run, once, from the table of kinds.

    ``k`` and ``r`` (paper section 3.1: ``r = sqrt(A / (k pi))``, or ``radius`` times
    the diagonal), clean-up and split-and-merge
    (:func:`superfacets.params.better_method`), the classification
    (:func:`superfacets.params.assignment_of`), the center tolerance (0.05 of ``r``
    with ``tol > 0``) and the coarsening (:func:`superfacets.multilevel.coarsening_for`).

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

    Returns
    -------
    Rules
    """
    k, radius = superfacet_size(p, graph.area, graph.diagonal, graph.n_elements, graph.kind)
    if n_centers is not None:
        k = int(min(max(n_centers, 1), graph.n_elements))
    radius = radius if r is None else r
    cleanup, split_merge = better_method(p, graph.kind)
    p = replace(p, assignment=assignment_of(p, graph.kind))
    center_tol = p.center_tol if p.center_tol is not None else (
        DEFAULT_CENTER_TOL if p.tol > 0 else 0.0)
    return Rules(params=p, kind=kind_of(graph.kind), k=k, r=radius, cleanup=cleanup,
                 split_merge=split_merge, center_tol=center_tol,
                 coarsen=coarsening_for(graph, p, k, radius))


def weigh(graph, rules: Rules, features=None) -> tuple[np.ndarray, np.ndarray | None]:
    """Stage 3: the weight of each adjacency, per CSR entry (paper eqs. 1-3, or
    Shlafman's eq. 6; with ``beta``, the feature term), and the swap energies'
    weights where split-and-merge runs (convex folds scaled by the kind's
    ``swap_eta_convex``).

    The adjacency terms stay cached on the graph for the clean-up when it runs;
    otherwise they are released (17 bytes per adjacency).

    Returns
    -------
    weights : (2 e,) float64 ndarray
    swap_weights : (2 e,) float64 ndarray or None
    """
    p = rules.params
    if rules.cleanup:
        graph.terms  # noqa: B018 (kept for the clean-up; else computed chunk by chunk)
    w_pairs = edge_weights(graph, p.weighting, alpha=p.alpha, eta_convex=p.eta_convex,
                           features=features, beta=p.beta)
    w = csr_weights(graph, w_pairs)
    del w_pairs  # the coarsening reads the same values from ``w``
    swap_w = None
    if rules.split_merge:  # the swap energies' weights (on faces: convex folds count half)
        from .weights import convex_scaled

        swap_w = convex_scaled(graph, w, alpha=p.alpha, eta_convex=p.eta_convex,
                               factor=rules.kind.swap_eta_convex, weighting=p.weighting)
    if not rules.cleanup:
        graph.release_terms()  # not needed again by this run
    return w, swap_w


def initialize(graph, w: np.ndarray, rules: Rules, hooks: "_Hooks",
               initial: np.ndarray | None = None) -> tuple[np.ndarray, int]:
    """Stage 4: the first centers (paper section 3.1, step 1): farthest point,
    flood or grid, after a coarse run on clusters where the rules say
    (:func:`superfacets.multilevel.start_centers`); or ``initial``.

    Returns
    -------
    centers : (c,) int64 ndarray
        Elements.
    coarsen : int
        The coarsening used (1: none).
    """
    if initial is not None:
        return np.asarray(initial, dtype=np.int64), 1
    return start_centers(graph, None, w, rules.params, rules.k, rules.r, rules.coarsen,
                         rules.center_tol, hooks.timings, hooks.describe,
                         on_coarsened=hooks.release_of(graph))


def iterate_passes(graph, w: np.ndarray, swap_w, init: np.ndarray, rules: Rules,
                   hooks: "_Hooks", *, replay: bool = True,
                   jump_cycles: bool = True) -> Iteration:
    """Stage 5: passes of (classify, update) until no center moves, ``tol`` or
    ``max_iter`` (paper section 3.1, steps 2-3); then, with split-and-merge, the
    K-preserving swaps and the passes again (with ``tol > 0``: the swaps once a pass
    changes at most ``START_TOL`` of the area, one round, then at most the kind's
    ``passes_after`` passes).

    Returns
    -------
    Iteration
    """
    p = rules.params
    spaces = Workspaces(graph.n_elements, w, p.n_threads)
    centers = np.empty(graph.n_elements, dtype=np.int64)
    centers[:init.shape[0]] = init
    sizes = np.ascontiguousarray(graph.sizes)
    positions = np.ascontiguousarray(graph.positions)
    min_move = rules.center_tol * rules.r
    try:
        classifier = make_classifier(p.assignment, graph, w, rules.window_r2, spaces,
                                     replay=replay)
        if rules.fast:
            from .splitmerge import START_TOL
        it = iterate(classifier, centers, init.shape[0], sizes, positions, p.max_iter,
                     jump_cycles=jump_cycles, tol=max(p.tol, START_TOL) if rules.fast else p.tol,
                     min_move=min_move, bar=hooks.bar)
        if rules.split_merge:
            from .splitmerge import FAST_ROUNDS, ROUNDS, swap_and_iterate

            hooks.describe("split and merge")
            it, hooks.timings["swaps"] = swap_and_iterate(
                it, graph, w, classifier, centers, sizes, positions, p.max_iter,
                window_r2=rules.window_r2, jump_cycles=jump_cycles, tol=p.tol,
                min_move=min_move, n_threads=spaces.n_threads,
                rounds=FAST_ROUNDS if rules.fast else ROUNDS,
                passes_after=rules.kind.passes_after if rules.fast else None,
                swap_weights=swap_w,
                hold_after=rules.kind.hold_after if rules.fast else 1.0)
    finally:
        spaces.close()
    return it


def finish(graph, label: np.ndarray, centers: np.ndarray, rules: Rules
           ) -> tuple[np.ndarray, np.ndarray]:
    """Stage 6: the labels of the last classification made dense (superfacets left
    empty dropped) and, unless the clean-up follows (it ends with it), each
    superfacet made connected (stray pieces merged into the neighbour sharing the
    longest border).

    Returns
    -------
    labels : (n,) int64 ndarray
    centers : (K,) int64 ndarray
        The centers of the superfacets kept.
    """
    present = np.zeros(centers.shape[0], dtype=bool)
    present[label] = True
    labels = relabel_dense(label)
    kept = centers[present]
    if rules.params.enforce_connectivity and not rules.cleanup:
        labels = _enforce_connectivity(graph, labels, kept)
    return labels, kept


def clean_up(graph, labels: np.ndarray, centers: np.ndarray, rules: Rules,
             features=None) -> np.ndarray:
    """Stage 7: the boundaries re-placed by minimum cuts within a band
    (:func:`superfacets.cleanup.clean_boundaries`; not in the paper), with the run's
    ``eta_convex``, ``alpha`` (the paper's default under another weighting) and
    feature term. The number of superfacets does not change.

    Returns
    -------
    (n,) int64 ndarray
    """
    p = rules.params
    return clean_boundaries(graph, labels, centers, radius=rules.r, eta_convex=p.eta_convex,
                            alpha=p.alpha if p.weighting == "paper" else _D.alpha,
                            connectivity=p.enforce_connectivity, n_threads=p.n_threads,
                            features=features, beta=p.beta)


def merge_small(graph, labels: np.ndarray, centers: np.ndarray, rules: Rules) -> np.ndarray:
    """Stage 8: superfacets of fewer than ``min_elements`` elements merged into the
    neighbour they share the longest border with (as stray pieces are; not in the
    paper).

    Returns
    -------
    (n,) int64 ndarray
    """
    return _enforce_connectivity(graph, labels, centers, min_elements=rules.params.min_elements)


class _Hooks:
    """What runs around the stages: their timings, the progress bar, and the
    release of the graph's arrays the passes do not read."""

    def __init__(self, progress: bool, max_iter: int, kind: str) -> None:
        self.timings: dict[str, float] = {}
        self.bar = None
        if progress:  # one bar: the set-up stages by name, then the passes
            from tqdm import tqdm

            self.bar = tqdm(total=max_iter, desc=f"{kind[:-1]} graph", unit="it", leave=False)

    def describe(self, name: str) -> None:
        if self.bar is not None:
            self.bar.set_description(name)

    @contextmanager
    def stage(self, key: str | None, name: str | None = None, add: bool = False):
        """Time a stage into ``timings[key]`` (added with ``add``); show ``name``."""
        if name is not None:
            self.describe(name)
        t = time.perf_counter()
        yield
        if key is not None:
            dt = time.perf_counter() - t
            self.timings[key] = self.timings.get(key, 0.0) + dt if add else dt

    @staticmethod
    def release_of(graph):
        """The graph's ``release``, for a graph large enough that it pays."""
        return graph.release if graph.n_elements >= _RELEASE_MIN else None

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()
            self.bar = None


def pipeline(mesh, params: SegmentParams, *, features=None, replay: bool = True,
             jump_cycles: bool = True, n_centers: int | None = None,
             initial: np.ndarray | None = None) -> SegmentationResult:
    """Run the method with validated parameters, stage by stage (see the module notes).

    Parameters
    ----------
    mesh : Mesh, trimesh.Trimesh, (vertices, faces), PointCloud or TetMesh
    params : SegmentParams
        From :func:`superfacets.params.resolve`.
    features : (N, d) float ndarray, optional
        One feature per input row, for ``params.beta > 0`` (default: the
        input's colours, if it has any).
    replay : bool, default True
        Replay the expansions of centers that did not move (bounded
        assignment); False expands every center on every pass. Same labels.
    jump_cycles : bool, default True
        Jump over a repeating cycle of center lists. Same labels.
    n_centers : int, optional
        Initial centers instead of the number ``radius`` gives (a tile of a
        tiled run: :mod:`superfacets.tiling`); ``r`` stays the radius's.
    initial : (c,) int ndarray, optional
        Elements to start the passes from, instead of the initialization
        (a tile starting from the whole run's centers).

    Returns
    -------
    SegmentationResult

    Raises
    ------
    ParameterError, InvalidMeshError, InvalidCloudError
        As :func:`superfacets.segment`.

    Examples
    --------
    >>> import trimesh
    >>> from superfacets.params import resolve
    >>> r = pipeline(trimesh.creation.icosphere(subdivisions=3), resolve(n_segments=20))
    >>> r.n_segments, sorted(r.timings)[:4]
    (20, ['changed', 'cleanup', 'connectivity', 'cycle_period'])
    """
    from ._threads import using

    with using(params.n_threads):  # also the graph build and terms this run triggers
        return _run(mesh, params, features, replay=replay, jump_cycles=jump_cycles,
                    n_centers=n_centers, initial=initial)


def _run(obj, p: SegmentParams, features, *, replay: bool, jump_cycles: bool,
         n_centers: int | None = None, initial=None) -> SegmentationResult:
    t_start = time.perf_counter()
    t = time.perf_counter()
    source, graph, p = build_graph(obj, p)
    t_graph = time.perf_counter() - t
    rules = resolve_rules(graph, p, n_centers=n_centers)
    p = rules.params
    feats = features_of(source, features) if p.beta > 0 else None
    hooks = _Hooks(p.progress, p.max_iter, graph.kind)
    hooks.timings["graph"] = t_graph
    try:
        with hooks.stage("weights", "weights"):
            w, swap_w = weigh(graph, rules, feats)
        with hooks.stage("init"):
            init, ratio = initialize(graph, w, rules, hooks, initial)
            release = hooks.release_of(graph)  # (again where no coarse run released them)
            if release is not None:
                release()
        with hooks.stage("iterations", "superfacets"):
            it = iterate_passes(graph, w, swap_w, init, rules, hooks, replay=replay,
                                jump_cycles=jump_cycles)
        w = swap_w = None  # free the weights before the clean-up
    except BaseException:
        hooks.close()
        raise
    if not rules.cleanup:
        hooks.close()
    sizes = np.ascontiguousarray(graph.sizes)
    positions = np.ascontiguousarray(graph.positions)
    with hooks.stage("connectivity"):
        labels, centers = finish(graph, it.label, it.centers, rules)
        centers = final_centers(labels, centers, sizes, positions)
    if rules.cleanup:
        try:
            with hooks.stage("cleanup", "clean-up"):
                labels = clean_up(graph, labels, centers, rules, feats)
        finally:
            hooks.close()
        centers = final_centers(labels, centers, sizes, positions)
    if p.min_elements > 1:  # small superfacets merged as stray pieces are (not the paper)
        with hooks.stage("connectivity", add=True):
            labels = merge_small(graph, labels, centers, rules)
            centers = final_centers(labels, centers, sizes, positions)
    timings = hooks.timings
    centers = source.first_rows(centers)
    element_labels = labels
    labels = source.to_rows(labels)
    timings["total"] = time.perf_counter() - t_start
    timings.update(expansions=it.expansions, passes=it.n_passes, cycle_period=it.cycle_period,
                   changed=it.changed, stopped_by_tol=it.stopped_by_tol)
    resolved = dict(n_segments=rules.k, radius=rules.r / graph.diagonal, alpha=p.alpha,
                    eta_convex=p.eta_convex, window=p.window, init=p.init,
                    max_iter=p.max_iter, weighting=p.weighting, assignment=p.assignment,
                    enforce_connectivity=p.enforce_connectivity, cleanup=rules.cleanup,
                    split_merge=rules.split_merge, tol=p.tol,
                    center_tol=rules.center_tol, coarsen=ratio,
                    n_init_centers=init.shape[0], elements=graph.kind, beta=p.beta,
                    min_elements=p.min_elements, density=p.density, roughness=p.roughness)
    if rules.kind.neighborhood:
        resolved.update(n_neighbors=p.n_neighbors, neighbor_radius=p.neighbor_radius)
    return SegmentationResult(labels=labels, centers=centers, n_iter=it.n_iter,
                              converged=it.converged, mesh_radius=rules.r,
                              n_orphan_seeds=it.n_orphan_seeds, timings=timings,
                              params=resolved, elements=source,
                              element_labels=element_labels)
