"""The stages of one run of the method, each entered once, in the paper's order.

:func:`superfacets.method.pipeline.pipeline` runs them (its notes list them); tiled runs
(:mod:`superfacets.scale.tiling`) call the same ones. Each stage takes what the one before
hands it: the element graph, the run's :class:`Rules` (every automatic rule
resolved once), the weights, the centers, the labels. :class:`Hooks` hold what runs
around them: timings, the progress bar, the release of memory.
"""

from __future__ import annotations

import time
from contextlib import contextmanager
from dataclasses import dataclass, replace

import numpy as np

from ..elements.inputs import ElementInput, elements_of, prepared
from ..elements.kinds import ElementKind, kind_of
from .adaptive import adapted_graph, density_for
from .classify import make_classifier
from .cleanup import clean_boundaries
from .connectivity import enforce_connectivity as _enforce_connectivity
from .expansion import Workspaces
from .labels import relabel_dense
from .multilevel import coarsening_for, start_centers
from .params import (
    DEFAULT_CENTER_TOL,
    DEFAULTS,
    SegmentParams,
    assignment_of,
    better_method,
    superfacet_size,
)
from .passes import Iteration, iterate
from .weights import csr_weights, edge_weights

__all__ = ["Rules", "Hooks", "build_graph", "resolve_rules", "weigh", "initialize",
           "iterate_passes", "finish", "clean_up", "merge_small", "exact_count"]

_D = DEFAULTS

#: Elements from which a run makes its graph forget, during the passes, the arrays
#: they do not read (:meth:`ElementGraph.release`: about 60 bytes per face of the
#: peak). Below it, rebuilding them after costs more than the memory is worth.
_RELEASE_MIN = 1 << 18


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


def build_graph(obj, p: SegmentParams, features=None
                ) -> tuple[ElementInput, object, SegmentParams]:
    """Stage 1: the input's element graph, with content-sensitive sizes where asked.

    ``n_segments`` is checked against the input's elements, and ``features`` (with
    ``beta > 0``) against its rows, before the graph is built (the memory peak of a
    run). ``density=None`` is resolved here, from the
    graph (:func:`superfacets.method.adaptive.density_for`); with ``density`` or
    ``roughness`` above 0 the returned graph's sizes are stretched
    (:func:`superfacets.method.adaptive.adapted_graph`; the cached graph is not changed).

    Returns
    -------
    source : ElementInput
    graph : ElementGraph
        The graph the method runs on.
    params : SegmentParams
        ``p`` with ``density`` resolved.
    """
    kind, data = prepared(obj, p.elements, n_segments=p.n_segments)
    if p.beta > 0:
        _check_features(kind, data, features)
    source = elements_of(data, kind, n_neighbors=p.n_neighbors,
                         neighbor_radius=p.neighbor_radius)
    graph = source.graph
    if p.density is None:  # automatic: superpoints follow a scan's uneven density
        p = replace(p, density=density_for(graph, p.paper))
    if p.density > 0 or p.roughness > 0:  # content-sensitive sizes (not in the paper)
        graph = adapted_graph(graph, p.density, p.roughness)
    return source, graph, p


def _check_features(kind: str, data, features) -> None:
    """``beta > 0``: features of one row per input row, or colours (materials) to use."""
    from ..errors import ParameterError

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


def resolve_rules(graph, p: SegmentParams, *, n_centers: int | None = None,
                  r: float | None = None) -> Rules:
    """Stage 2: every automatic rule of the run, once, from the table of kinds.

    ``k`` and ``r`` (paper section 3.1: ``r = sqrt(A / (k pi))``, or ``radius`` times
    the diagonal), clean-up and split-and-merge
    (:func:`superfacets.method.params.better_method`), the classification
    (:func:`superfacets.method.params.assignment_of`), the center tolerance (0.05 of ``r``
    with ``tol > 0``) and the coarsening (:func:`superfacets.method.multilevel.coarsening_for`).

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


def initialize(graph, w: np.ndarray, rules: Rules, hooks: Hooks,
               initial: np.ndarray | None = None) -> tuple[np.ndarray, int]:
    """Stage 4: the first centers (paper section 3.1, step 1): farthest point,
    flood or grid, after a coarse run on clusters where the rules say
    (:func:`superfacets.method.multilevel.start_centers`); or ``initial``.

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
                   hooks: Hooks, *, replay: bool = True,
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
    (:func:`superfacets.method.cleanup.clean_boundaries`; not in the paper), with the run's
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


def exact_count(graph, labels: np.ndarray, rules: Rules) -> tuple[np.ndarray, int]:
    """Stage 9 (kinds with ``exact_count``: points): a run asked for ``k`` that made more
    segments (regions no window reached seed their own) merges adjacent ones, cheapest
    first (:func:`superfacets.graph.hierarchy.hierarchy`, Ward's cost with the run's
    crease factor), down to ``k``, or to the input's number of separate pieces where
    that is more: a region cannot cross from one piece to another.

    Returns
    -------
    labels : (n,) int64 ndarray
    fewest : int
        The count the run could reach: ``k``, or the pieces where there are more.
    """
    from ..graph.adjacency import superfacet_graph
    from ..graph.hierarchy import hierarchy, pieces

    k, n = rules.k, int(labels.max()) + 1 if labels.size else 0
    if k is None or n <= k:
        return labels, n
    sg = superfacet_graph(graph, labels)
    fewest = max(k, pieces(sg))
    if n <= fewest:
        return labels, fewest
    p = rules.params
    level = hierarchy(sg, [fewest], alpha=p.alpha, eta_convex=p.eta_convex)
    return level.labels(0, labels).astype(np.int64), fewest


class Hooks:
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
