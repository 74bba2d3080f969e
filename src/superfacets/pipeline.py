"""One run of the superfacet method, step by step (paper section 3; ``docs/method.md``).

:func:`pipeline` takes validated parameters (:func:`superfacets.params.resolve`;
the public functions of :mod:`superfacets.segmentation` call it) and returns a
:class:`SegmentationResult`:

1. parameters validated (:func:`superfacets.params.resolve`), before any work;
2. element graph (the face graph of the mesh, cached on it); with ``density`` or
   ``roughness``, its sizes stretched (:mod:`superfacets.adaptive`);
3. weights (paper eqs. 1-3, or Shlafman's eq. 6);
4. initial centers (farthest point, flood or grid);
5. passes of (classify, update) until no center moves or ``max_iter``
   (:mod:`superfacets.passes`, with a strategy of :mod:`superfacets.classify`);
6. empty superfacets dropped, stray pieces merged (connectivity);
   with ``split_merge=True``, rounds of K-preserving swaps, each followed by
   the passes again (:mod:`superfacets.splitmerge`; with ``tol > 0`` the swaps
   come once a pass changes at most ``START_TOL`` of the area, one round, and at
   most ``passes_after_for(kind)`` passes follow);
7. with ``cleanup=True``, the boundaries re-placed (:mod:`superfacets.cleanup`);
8. with ``min_elements > 1``, superfacets of fewer elements merged into a neighbour;
9. the result.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field, replace

import numpy as np

from .adaptive import adapted_graph, density_for
from .classify import make_classifier
from .cleanup import clean_boundaries
from .connectivity import enforce_connectivity as _enforce_connectivity
from .expansion import Workspaces
from .labels import relabel_dense
from .elements.inputs import elements_of
from .elements.kinds import kind_of
from .multilevel import start_centers
from .params import (DEFAULT_CENTER_TOL, DEFAULTS, SegmentParams, assignment_of, better_method,
                     superfacet_size)
from .passes import final_centers, iterate
from .weights import csr_weights, edge_weights

__all__ = ["pipeline", "SegmentationResult"]

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
    radius : float
        Superfacet radius ``r`` used, in mesh units.
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
    radius: float
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
                  compactness: float | None = None):
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
        compactness : float, optional
            With ``cost='planarity'``, the weight of the segments' extent
            (:func:`superfacets.hierarchy.hierarchy`). Default: left to the
            method, :func:`~superfacets.hierarchy.level_compactness` (0.01 on
            a scan of uneven density, else 0).

        Returns
        -------
        Hierarchy
            ``.parents[i]``: the parent of each segment of the level below;
            ``.labels(i, result.labels)``: one label per input row at level ``i``.

        Raises
        ------
        ParameterError
            If a level is out of range.
        """
        from .hierarchy import hierarchy, level_compactness, planarity_graph

        if cost == "planarity":
            src = self._source()
            graph = planarity_graph(src.graph, self.element_labels, _per_element(
                src, src.colors() if features is None else features))
            if compactness is None:
                compactness = level_compactness(src.graph)
        else:
            graph = self.graph(features)
        return hierarchy(graph, levels, alpha=self.params.get("alpha", 200.0),
                         eta_convex=self.params.get("eta_convex", 0.2), beta=beta, cost=cost,
                         compactness=compactness or 0.0)

    def _source(self):
        if self.elements is None or self.element_labels is None:
            from .errors import ParameterError

            raise ParameterError("this result holds no element graph (made by hand?): use "
                                 "superfacets.adjacency.superfacet_graph(graph, labels)")
        return self.elements


def _features_of(src, features):
    """The per-element features of a run with ``beta > 0``: ``features`` (one row per
    input row), else the input's colours."""
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


def pipeline(mesh, params: SegmentParams, *, features=None, replay: bool = True,
             jump_cycles: bool = True, n_centers: int | None = None,
             initial: np.ndarray | None = None) -> SegmentationResult:
    """Run the method with validated parameters (see the module notes).

    Parameters
    ----------
    mesh : Mesh, trimesh.Trimesh or (vertices, faces)
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
    """
    from ._threads import using

    with using(params.n_threads):  # also the graph build and terms this run triggers
        return _pipeline(mesh, params, features, replay=replay, jump_cycles=jump_cycles,
                         n_centers=n_centers, initial=initial)


def _pipeline(mesh, params: SegmentParams, features, *, replay: bool, jump_cycles: bool,
              n_centers: int | None = None, initial=None) -> SegmentationResult:
    t_start = time.perf_counter()
    p = params
    t = time.perf_counter()
    source = elements_of(mesh, p.elements, n_neighbors=p.n_neighbors,
                         neighbor_radius=p.neighbor_radius)
    graph = source.graph
    if p.density is None:  # automatic: superpoints follow a scan's uneven density
        p = replace(p, density=density_for(graph, p.paper))
    if p.density > 0 or p.roughness > 0:  # content-sensitive sizes (not in the paper)
        graph = adapted_graph(graph, p.density, p.roughness)
    t_graph = time.perf_counter() - t
    k, r = superfacet_size(p, graph.area, graph.diagonal, graph.n_elements, graph.kind)
    if n_centers is not None:
        k = int(min(max(n_centers, 1), graph.n_elements))
    cleanup, split_merge = better_method(p, graph.kind)
    p = replace(p, assignment=assignment_of(p, graph.kind))
    feats = _features_of(source, features) if p.beta > 0 else None
    timings: dict[str, float] = {}
    bar = None
    if p.progress:  # one bar: the set-up stages by name, then the passes
        from tqdm import tqdm

        bar = tqdm(total=p.max_iter, desc=f"{graph.kind[:-1]} graph", unit="it", leave=False)
    try:
        timings["graph"] = t_graph

        _stage(bar, "weights")
        t = time.perf_counter()
        if cleanup:
            graph.terms  # noqa: B018 (kept for the clean-up; else computed chunk by chunk)
        w_pairs = edge_weights(graph, p.weighting, alpha=p.alpha, eta_convex=p.eta_convex,
                               features=feats, beta=p.beta)
        w = csr_weights(graph, w_pairs)
        del w_pairs  # the coarsening reads the same values from ``w``
        swap_w = None
        if split_merge:  # the swap energies' weights (on faces: convex folds count half)
            from .splitmerge import swap_eta_convex_for
            from .weights import convex_scaled

            swap_w = convex_scaled(graph, w, alpha=p.alpha, eta_convex=p.eta_convex,
                                   factor=swap_eta_convex_for(graph.kind), weighting=p.weighting)
        if not cleanup:
            graph.release_terms()  # not needed again by this run; 17 B per adjacency
        timings["weights"] = time.perf_counter() - t

        window_r2 = (p.window * r) ** 2
        t = time.perf_counter()
        if initial is None:
            # what the passes do not read (rebuilt after them), freed from the coarse run on
            release = graph.release if graph.n_elements >= _RELEASE_MIN else None
            init, center_tol, ratio = start_centers(graph, None, w, p, k, r, timings,
                                                    lambda name: _stage(bar, name),
                                                    on_coarsened=release)
        else:
            init, ratio = np.asarray(initial, dtype=np.int64), 1
            center_tol = p.center_tol if p.center_tol is not None else (
                DEFAULT_CENTER_TOL if p.tol > 0 else 0.0)
        if graph.n_elements >= _RELEASE_MIN:  # (again where no coarse run released them)
            graph.release()
        spaces = Workspaces(graph.n_elements, w, p.n_threads)
        timings["init"] = time.perf_counter() - t

        _stage(bar, "superfacets")
        t = time.perf_counter()
        centers = np.empty(graph.n_elements, dtype=np.int64)
        centers[:init.shape[0]] = init
        sizes = np.ascontiguousarray(graph.sizes)
        positions = np.ascontiguousarray(graph.positions)
        try:
            classifier = make_classifier(p.assignment, graph, w, window_r2, spaces,
                                         replay=replay)
            fast = split_merge and p.tol > 0  # swaps early, few passes after them
            if fast:
                from .splitmerge import FAST_ROUNDS, START_TOL, passes_after_for
            it = iterate(classifier, centers, init.shape[0], sizes, positions, p.max_iter,
                         jump_cycles=jump_cycles, tol=max(p.tol, START_TOL) if fast else p.tol,
                         min_move=center_tol * r, bar=bar)
            if split_merge:
                from .splitmerge import ROUNDS, hold_after_for, swap_and_iterate

                _stage(bar, "split and merge")
                it, timings["swaps"] = swap_and_iterate(
                    it, graph, w, classifier, centers, sizes, positions, p.max_iter,
                    window_r2=window_r2, jump_cycles=jump_cycles, tol=p.tol,
                    min_move=center_tol * r, n_threads=spaces.n_threads,
                    rounds=FAST_ROUNDS if fast else ROUNDS,
                    passes_after=passes_after_for(graph.kind) if fast else None,
                    swap_weights=swap_w,
                    hold_after=hold_after_for(graph.kind) if fast else 1.0)
        finally:
            spaces.close()
        classifier = spaces = w = swap_w = None  # free the work buffers before the clean-up
        timings["iterations"] = time.perf_counter() - t
    except BaseException:
        if bar is not None:
            bar.close()
        raise
    if bar is not None and not cleanup:
        bar.close()

    # labels of the last classification; drop superfacets left empty
    t = time.perf_counter()
    present = np.zeros(it.centers.shape[0], dtype=bool)
    present[it.label] = True
    labels = relabel_dense(it.label)
    centers = it.centers[present]
    if p.enforce_connectivity and not cleanup:  # the clean-up ends with it
        labels = _enforce_connectivity(graph, labels, centers)
    centers = final_centers(labels, centers, sizes, positions)
    timings["connectivity"] = time.perf_counter() - t
    if cleanup:
        _stage(bar, "clean-up")
        t = time.perf_counter()
        try:
            labels = clean_boundaries(graph, labels, centers, radius=r, eta_convex=p.eta_convex,
                                      alpha=p.alpha if p.weighting == "paper" else _D.alpha,
                                      connectivity=p.enforce_connectivity, n_threads=p.n_threads,
                                      features=feats, beta=p.beta)
        finally:
            if bar is not None:
                bar.close()
        centers = final_centers(labels, centers, sizes, positions)
        timings["cleanup"] = time.perf_counter() - t
    if p.min_elements > 1:  # small superfacets merged as stray pieces are (not the paper)
        t = time.perf_counter()
        labels = _enforce_connectivity(graph, labels, centers, min_elements=p.min_elements)
        centers = final_centers(labels, centers, sizes, positions)
        timings["connectivity"] += time.perf_counter() - t
    centers = source.first_rows(centers)
    element_labels = labels
    labels = source.to_rows(labels)
    timings["total"] = time.perf_counter() - t_start
    timings.update(expansions=it.expansions, passes=it.n_passes, cycle_period=it.cycle_period,
                   changed=it.changed, stopped_by_tol=it.stopped_by_tol)
    resolved = dict(n_segments=k, radius=r / graph.diagonal, alpha=p.alpha,
                    eta_convex=p.eta_convex, window=p.window, init=p.init,
                    max_iter=p.max_iter, weighting=p.weighting, assignment=p.assignment,
                    enforce_connectivity=p.enforce_connectivity, cleanup=cleanup,
                    split_merge=split_merge, tol=p.tol,
                    center_tol=center_tol, coarsen=ratio,
                    n_init_centers=init.shape[0], elements=graph.kind, beta=p.beta,
                    min_elements=p.min_elements, density=p.density, roughness=p.roughness)
    if kind_of(graph.kind).neighborhood:
        resolved.update(n_neighbors=p.n_neighbors, neighbor_radius=p.neighbor_radius)
    return SegmentationResult(labels=labels, centers=centers, n_iter=it.n_iter,
                              converged=it.converged, radius=r,
                              n_orphan_seeds=it.n_orphan_seeds, timings=timings,
                              params=resolved, elements=source,
                              element_labels=element_labels)


def _stage(bar, name: str) -> None:
    if bar is not None:
        bar.set_description(name)

