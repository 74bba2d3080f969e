"""One run of the superfacet method, as named stages (paper section 3;
``docs/notes/method.md``).

:func:`pipeline` takes validated parameters (:func:`superfacets.method.params.resolve`;
the public functions of :mod:`superfacets.api.segmentation` call it) and runs the stages
of :mod:`superfacets.method.stages` and :mod:`superfacets.method.finish`, each entered
once and in the paper's order
(Algorithm 1):

1. ``build_graph``: the element graph (``n_segments`` checked against the input's
   elements first); with ``density`` (resolved here: it reads the graph) or
   ``roughness``, its sizes stretched (:mod:`superfacets.elements.density`);
2. ``resolve_features`` (where the input has colours or features: the colour term's
   weight and the features' noise, read from the data) and ``resolve_rules``: the
   automatic rules, once: ``k`` and the radius ``r`` (section
   3.1), clean-up and split-and-merge, the classification, the center tolerance and the
   coarsening, from the table of kinds (:mod:`superfacets.elements.kinds`);
3. ``weigh``: the adjacency weights (eqs. 1-3, or Shlafman's eq. 6), and the swap
   energies' weights;
4. ``initialize``: the first centers (farthest point, flood or grid, after a coarse run
   on clusters where it pays: :mod:`superfacets.method.coarse_to_fine`);
5. ``iterate_passes``: passes of (classify, update) until no center moves, ``tol`` or
   ``max_iter`` (:mod:`superfacets.method.passes`, with a strategy of
   :mod:`superfacets.method.classify`); with split-and-merge, the K-preserving swaps
   and the passes again (:mod:`superfacets.method.splitmerge`);
6. ``finish``: empty superfacets dropped, labels made dense, stray pieces merged
   (connectivity);
7. ``clean_up``: the boundaries re-placed (:mod:`superfacets.method.cleanup`);
8. ``merge_small``: superfacets of fewer than ``min_elements`` merged.
9. ``exact_count`` (kinds that ask for it: points, cells): the count made exactly ``k``; where
   ``merge_from > 1`` (points of even density), ``merge_to_count`` instead: the run's
   ``merge_from`` times ``k`` superpoints merged to ``k``, flat neighbours first
   (:mod:`superfacets.method.merges`).

Each stage declares what it reads (:func:`~superfacets.method.stages.stage_reads`);
timings, the progress bar and the one place that forgets what no later stage reads
are hooks around the stages (:class:`Hooks`), not inside them. Tiled runs
(:mod:`superfacets.scale.tiles.phases`) call the same stages.
"""

from __future__ import annotations

import time
from contextlib import contextmanager
from typing import NamedTuple

import numpy as np

from .._runtime import interrupts
from .._runtime.memory import give_back_free_memory
from .._runtime.progress import new_bar, tick
from .._runtime.threads import using
from ..elements.builders import kind_for
from ..elements.kinds import kind_of
from ..elements.labels import relabel_dense
from . import stages
from .finish import clean_up, exact_count, finish, merge_small
from .merges import merge_to_count
from .params import ALL_KINDS, PARAMETERS, SegmentParams, resolve
from .passes import final_centers
from .stages import (
    build_graph,
    held_weights,
    initialize,
    iterate_passes,
    resolve_features,
    resolve_rules,
    stage_reads,
    weigh,
)
from .weights import weights_array

__all__ = ["pipeline", "RunRecord", "Hooks", "passes_example"]


class RunRecord(NamedTuple):
    """What one run of the method gives: the fields of
    :class:`superfacets.api.result.SegmentationResult`, which wraps it (the method sits
    below the public API).

    Examples
    --------
    >>> run = pipeline(trimesh.creation.icosphere(subdivisions=2), resolve(n_segments=8))
    >>> run.labels.shape, int(run.labels.max()) + 1
    ((320,), 8)
    >>> sorted(set(run._asdict()) - set(run.result_fields()))
    ['classification']
    """

    labels: np.ndarray
    centers: np.ndarray
    n_iter: int
    converged: bool
    mesh_radius: float
    n_orphan_seeds: int
    timings: dict
    params: dict
    elements: object
    element_labels: np.ndarray
    classification: tuple | None = None

    def result_fields(self) -> dict:
        """The fields a :class:`~superfacets.api.result.SegmentationResult` holds: all but
        ``classification`` (the last pass of an unfinished run, for a tile's later phase)."""
        fields = self._asdict()
        del fields["classification"]
        return fields


#: Elements from which a run makes its graph forget, during the passes, the arrays
#: they do not read (:meth:`ElementGraph.release`: about 60 bytes per face of the
#: peak). Below it, rebuilding them after costs more than the memory is worth.
_RELEASE_MIN = 1 << 18


class Hooks:
    """What runs around the stages: their timings, the progress bar, the
    release of the graph's arrays no later stage reads (:meth:`before`), and, on large
    graphs (``trim``), the allocator's free memory handed back before the passes.

    Parameters
    ----------
    progress : bool
        Show a progress bar (tqdm) on stderr, from the start of the graph's build.
    max_iter : int
        The most passes (the bar counts the passes run, with no length: a run stops
        where it converges, mostly well before ``max_iter``, so a remaining time
        reckoned from it would be wrong).
    kind : str
        The kind of element, for the bar's first description.

    Examples
    --------
    >>> hooks = Hooks(False, 50, "faces")
    >>> with hooks.stage("weights"):
    ...     pass
    >>> sorted(hooks.timings)
    ['weights']
    """

    def __init__(self, progress: bool, max_iter: int, kind: str) -> None:
        self.timings: dict[str, float] = {}
        self.graph, self.plan = None, ()  # what before() forgets of (follow())
        self.trim = False  # free memory handed back before the passes (large graphs)
        self.bar = None
        self._ticking = None
        if progress:  # one bar: the set-up stages by name, then the passes
            self.bar = new_bar(total=None, desc=f"{kind_of(kind).singular} graph", unit="pass",
                               leave=False)
            self.bar.refresh()  # (shown at once: the graph's build is a run's longest wait)
            self._ticking = tick(self.bar)

    def describe(self, name: str) -> None:
        if self.bar is not None:
            self.bar.set_description_str(name)

    @contextmanager
    def stage(self, key: str | None, name: str | None = None, add: bool = False):
        """Time a stage into ``timings[key]`` (added with ``add``); show ``name``. A Ctrl-C
        the command line could not raise where it came is raised here, first."""
        interrupts.check()
        if name is not None:
            self.describe(name)
        t = time.perf_counter()
        yield
        if key is not None:
            dt = time.perf_counter() - t
            self.timings[key] = self.timings.get(key, 0.0) + dt if add else dt

    def follow(self, graph, plan) -> None:
        """Forget, from now on, what ``graph``'s later stages do not read: ``plan`` is
        :func:`~superfacets.method.stages.stage_reads`."""
        self.graph, self.plan = graph, plan

    def before(self, stage: str) -> None:
        """The one place a run forgets: before ``stage`` (a stage of the plan given to
        :meth:`follow`), the fields of the graph that neither it nor a later stage reads.

        On a graph of :data:`_RELEASE_MIN` elements or more, "later" ends at the passes
        (which read no such field and are a run's memory peak: the stages after them make
        again what they read); the terms and border lengths a stage reads are made before
        their ingredients (normals, pairs, a triangle mesh's edges) go. On a smaller graph
        only the terms no later stage reads are forgotten (making the others again would
        cost more than their memory is worth).
        """
        graph, plan = self.graph, self.plan
        if graph is None:
            return
        names = [name for name, _ in plan]
        i = names.index(stage)
        passes = names.index("passes")
        ahead = [fields for _, fields in plan[i:passes if i <= passes else None]]
        needed = set().union(*ahead)
        if graph.n_elements < _RELEASE_MIN:
            if "terms" not in set().union(*(fields for _, fields in plan[i:])):
                graph.release_terms()
            return
        reads = plan[i][1]
        if "terms" in reads:
            graph.terms  # noqa: B018 (made here, so that their ingredients can go)
        elif "terms" in needed and "terms" not in graph.__dict__:
            needed |= {"normals", "pairs", "edges"}  # (what a later stage makes them from)
        if ("edges" in graph.rebuild and "lengths" in needed
                and "lengths" not in graph.__dict__):  # (a triangle mesh's edges: the
            if "lengths" not in reads:  # border lengths' ingredient)
                needed.add("edges")
            else:  # made here, once the terms' other ingredients went
                graph.release(keep=tuple(needed | {"edges"}))
                graph.lengths  # noqa: B018
        if "terms" not in needed:
            graph.release_terms()
        graph.release(keep=tuple(needed))

    def close(self) -> None:
        if self._ticking is not None:
            self._ticking.set()
            self._ticking = None
        if self.bar is not None:
            self.bar.close()
            self.bar = None



def pipeline(mesh, params: SegmentParams, *, features=None, replay: bool = True,
             jump_cycles: bool = True, n_centers: int | None = None,
             initial: np.ndarray | None = None, finished: bool = True,
             order: np.ndarray | None = None, fixed: np.ndarray | None = None,
             feature_floor: float | None = None) -> RunRecord:
    """Run the method with validated parameters, stage by stage (see the module notes).

    Parameters
    ----------
    mesh : Mesh, trimesh.Trimesh, (vertices, faces), PointCloud or TetMesh
    params : SegmentParams
        From :func:`superfacets.method.params.resolve`.
    features : (N, d) float ndarray, optional
        One feature per input row, for the colour term (default: the input's colours,
        if it has any; ``params.beta`` None reads the term's weight from them).
    replay : bool, default True
        Replay the expansions of centers that did not move (bounded
        assignment); False expands every center on every pass. Same labels.
    jump_cycles : bool, default True
        Jump over a repeating cycle of center lists. Same labels.
    n_centers : int, optional
        Initial centers instead of the number ``radius`` gives (a tile of a
        tiled run: :mod:`superfacets.scale.tiles.phases`); ``r`` stays the radius's.
    initial : (c,) int ndarray, optional
        Elements to start the passes from, instead of the initialization
        (a tile starting from the whole run's centers).
    finished : bool, default True
        False: the last pass's labels and centers (those that kept an element), without
        the finishing stages (connectivity, clean-up, merges): a tile's centers and refine
        phases, which keep only centers, the labels phase finishing once.
    order : (n,) int64 ndarray, optional
        A distinct key per element: the passes list their centers by it
        (:func:`superfacets.method.passes.iterate`; a tile's refine round, by row). With
        ``finished=False`` the record's ``classification`` is the last pass's: each
        element's superfacet (int32, an index into the centers), the centers (elements,
        int64), each element's distance to its center (float64) and the passes'
        classifier (whose recorded expansions a tile's labels phase replays).
    fixed : (n,) bool ndarray, optional
        Elements whose centers stay where they are through the passes and take no part in
        a swap (a tile's refine round: the centers of its halo, its neighbours' to move;
        :func:`superfacets.method.passes.iterate`).
    feature_floor : float, optional
        With ``params.beta`` a number: the colour term's floor, not read from this input
        (a tiled run reads it once for every tile: :func:`resolve_features`).

    Returns
    -------
    RunRecord
        The labels and details (:func:`superfacets.segment` wraps them as a
        :class:`~superfacets.api.result.SegmentationResult`).

    Raises
    ------
    ParameterError, InvalidMeshError, InvalidCloudError
        As :func:`superfacets.segment`.

    Examples
    --------
    >>> r = pipeline(trimesh.creation.icosphere(subdivisions=3), resolve(n_segments=20))
    >>> len(r.centers), sorted(r.timings)[:4]
    (20, ['changed', 'cleanup', 'connectivity', 'cycle_period'])
    """

    with using(params.n_threads):  # also the graph build and terms this run triggers
        return _run(mesh, params, features, replay=replay, jump_cycles=jump_cycles,
                    n_centers=n_centers, initial=initial, finished=finished, order=order,
                    fixed=fixed, feature_floor=feature_floor)


def _run(obj, p: SegmentParams, features, *, replay: bool, jump_cycles: bool,
         n_centers: int | None = None, initial=None, finished: bool = True,
         order=None, fixed=None, feature_floor=None) -> RunRecord:
    t_start = time.perf_counter()
    hooks = Hooks(p.progress, p.max_iter, kind_for(obj, p.elements))
    try:
        with hooks.stage("graph"):
            source, graph, p = build_graph(obj, p, features)
        with hooks.stage("features"):  # (the colour term's weight and floor, where read)
            p, feats, floor = resolve_features(source, graph, p, features, feature_floor)
        rules = resolve_rules(graph, p, n_centers=n_centers, feature_floor=floor,
                              scene=getattr(source.source, "up", None) is not None)
        hooks.follow(graph, stage_reads(rules, initial))
        p = rules.params
    except BaseException:
        hooks.close()
        raise
    if graph.n_elements >= _RELEASE_MIN:  # the build's temporaries handed back, and the
        hooks.trim = True  # weights' and the start's before the passes (not after every
        give_back_free_memory()  # stage: the next stages fault the pages in again)
    try:
        with hooks.stage("weights", "weights"):
            w, swap_w = weigh(graph, rules, feats, hooks)
        with hooks.stage("init"):  # (the coarse start may let the weights go: held)
            held = held_weights(graph, rules, w, feats, initial) if hooks.trim else w
            del w
            init, ratio = initialize(graph, held, rules, hooks, initial)
        with hooks.stage("weights", add=True):  # (made again where they were let go)
            w = weights_array(held)
            del held
        with hooks.stage("init", add=True):
            hooks.before("passes")  # (again: where no coarse run forgot, or the weights
            if hooks.trim:  # were made again) the passes start without the build's and
                give_back_free_memory()  # the start's freed temporaries (a mesh's peak)
        with hooks.stage("iterations", "superfacets"):
            it = iterate_passes(graph, w, swap_w, init, rules, hooks, replay=replay,
                                jump_cycles=jump_cycles, order=order, fixed=fixed,
                                keep_classifier=not finished)
        w = swap_w = None  # free the weights before the clean-up
    except BaseException:
        hooks.close()
        raise
    try:
        labels, centers = (_finished(graph, it, rules, hooks, feats) if finished
                           else _unfinished(it))
    finally:
        hooks.close()
    timings = hooks.timings
    centers = source.first_rows(centers)
    element_labels = labels
    labels = source.to_rows(labels)
    timings["total"] = time.perf_counter() - t_start
    timings.update(expansions=it.expansions, passes=it.n_passes, cycle_period=it.cycle_period,
                   changed=it.changed, stopped_by_tol=it.stopped_by_tol, settled=it.settled)
    return RunRecord(labels=labels, centers=centers, n_iter=it.n_iter, converged=it.converged,
                     mesh_radius=rules.r, timings=timings,  # (the coarse run's orphans too)
                     n_orphan_seeds=it.n_orphan_seeds + int(timings.get("coarse_orphans", 0)),
                     params=_resolved(graph, rules, ratio, init.shape[0]), elements=source,
                     element_labels=element_labels,
                     classification=None if finished else (it.label, it.centers, it.dist,
                                                            it.classifier))


def _unfinished(it) -> tuple[np.ndarray, np.ndarray]:
    """The last pass's labels made dense, and the centers that kept an element."""
    present = np.zeros(it.centers.shape[0], dtype=bool)
    present[it.label] = True
    return relabel_dense(it.label), np.asarray(it.centers, dtype=np.int64)[present]


def _finished(graph, it, rules, hooks, feats):
    """The labels and centers after the passes: connected, cleaned up, small ones merged,
    exactly the count asked for where the kind wants it (the finishing stages)."""
    p = rules.params
    sizes = np.ascontiguousarray(graph.sizes)
    positions = np.ascontiguousarray(graph.positions)
    with hooks.stage("connectivity", "connectivity"):
        labels, centers = finish(graph, it.label, it.centers, rules)
        centers = final_centers(labels, centers, sizes, positions)
    if rules.cleanup:
        with hooks.stage("cleanup", "clean-up"):
            hooks.before("clean-up")
            labels = clean_up(graph, labels, centers, rules, feats,  # (a large graph's
                              bands_found=(lambda: hooks.before("cuts")) if hooks.trim
                              else None)  # terms, lengths, dual-edge map let go for its cuts)
        centers = final_centers(labels, centers, sizes, positions)
    if p.min_elements > 1:  # small superfacets merged as stray pieces are (not the paper)
        with hooks.stage("connectivity", add=True):
            labels = merge_small(graph, labels, centers, rules)
            centers = final_centers(labels, centers, sizes, positions)
    merging = rules.target is not None and rules.target < rules.k  # merge_from > 1
    if merging or (rules.kind.exact_count and p.n_segments is not None and not p.paper
                   and p.min_elements == 1):  # exactly the k asked for (not the paper)
        with hooks.stage("merges" if merging else "connectivity",
                         "merges to the count" if merging else None, add=True):
            labels, fewest = (merge_to_count(graph, labels, rules, feats) if merging else
                              exact_count(graph, labels, rules))
            centers = final_centers(labels, centers, sizes, positions)
        if fewest > rules.target:
            import warnings

            warnings.warn(f"{fewest} superpoints for n_segments={rules.target}: the input has "
                          f"{fewest} separate pieces, and a superpoint cannot cross from one "
                          "to another", RuntimeWarning, stacklevel=4)
    _say_min_elements(labels, p, rules)
    return labels, centers


def _say_min_elements(labels: np.ndarray, p, rules) -> None:
    """Warn where ``min_elements`` left fewer segments than asked for."""
    made = int(labels.max()) + 1 if labels.size else 0
    if p.min_elements > 1 and p.n_segments is not None and made < p.n_segments:
        import warnings

        warnings.warn(f"{made} {rules.kind.segment_word} for n_segments={p.n_segments}: "
                      f"min_elements={p.min_elements} merged those of fewer elements into "
                      "their neighbours", RuntimeWarning, stacklevel=4)


#: Parameters of how a run is carried out, not of its result: not in its record
_NOT_RECORDED = ("progress", "n_threads", "paper")


def _resolved(graph, rules, ratio, n_init: int) -> dict:
    """The run's parameters as the method resolved them (``SegmentationResult.params``):
    every declared parameter of the graph's kind (:data:`~superfacets.method.params.
    PARAMETERS`) but those of how it ran, with the values the method settled on."""
    p = rules.params
    resolved = {q.name: getattr(p, q.name) for q in PARAMETERS  # (a kind's own, or all's)
                if q.name not in _NOT_RECORDED and (q.kinds == ALL_KINDS or graph.kind in q.kinds)}
    resolved.update(n_segments=rules.target, radius=rules.r / graph.diagonal,
                    cleanup=rules.cleanup, split_merge=rules.split_merge,
                    center_tol=rules.center_tol, coarsen=ratio, elements=graph.kind,
                    n_init_centers=n_init)
    if p.beta > 0:  # the colour term's noise floor (read from the data)
        resolved["feature_floor"] = rules.feature_floor
    return resolved


def passes_example(n_segments: int = 12):
    """A run up to its passes, on an icosphere of 1,280 faces: the set-up the examples of
    the later stages share (:mod:`superfacets.method.finish`).

    Parameters
    ----------
    n_segments : int, default 12

    Returns
    -------
    types.SimpleNamespace
        ``graph``, ``rules``, ``hooks``, ``w``, ``swap_w``, ``init``, ``it`` (the
        passes' :class:`~superfacets.method.passes.Iteration`), and ``labels`` and
        ``kept``, the passes' labels and centers as :func:`finish` leaves them.

    Raises
    ------
    ParameterError
        If ``n_segments`` is not in ``1..1280``.

    Examples
    --------
    >>> s = passes_example()
    >>> s.graph.n_elements, s.rules.k, int(s.it.label.max()) + 1
    (1280, 12, 12)
    """
    from types import SimpleNamespace

    import trimesh

    ball = trimesh.creation.icosphere(subdivisions=3)
    _, graph, p = build_graph(ball, resolve(n_segments=n_segments))
    rules = resolve_rules(graph, p)
    hooks = Hooks(False, p.max_iter, graph.kind)
    w, swap_w = weigh(graph, rules)
    init, _ = initialize(graph, w, rules, hooks)
    it = stages.iterate_passes(graph, w, swap_w, init, rules, hooks)
    labels, kept = finish(graph, it.label, it.centers, rules)
    return SimpleNamespace(graph=graph, rules=rules, hooks=hooks, w=w, swap_w=swap_w,
                           init=init, it=it, labels=labels, kept=kept)
