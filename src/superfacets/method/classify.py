"""The classification step of the iteration: strategies behind one interface.

A :class:`Classifier` labels every element with a center, given the centers
of the pass (paper section 3.1, step 2); elements no center reached (orphans)
seed new centers, appended to the center list. The strategies:

- :class:`BoundedReplay` (``assignment='bounded'``, the default on faces and
  points): the paper's window-bounded expansion from each center, an element keeping the smallest
  distance seen (the earlier center on ties). An expansion depends on its
  center alone, so a center that did not move since the previous pass is not
  expanded again: its recorded (element, distance) list is replayed. The
  centers that moved are expanded on ``n_threads`` threads at once; records
  are merged by the lexicographic (distance, center index) rule, so the
  labels are exactly those of :class:`Bounded`, for any thread count.
- :class:`Bounded`: the same classification written plainly (every center
  expanded every pass, in order); the reference of the tests.
- :class:`Exact` (``assignment='exact'``, the default on vertices): one
  multi-source search from all centers, no window: every element goes to its
  nearest center (ties: the center listed first); after the first pass, the
  cells of the centers that did not move are kept and the rest searched again.

:func:`make_classifier` picks one by name.
"""

from __future__ import annotations

import numpy as np

from .._kernels import native
from .._kernels.codes import NOT_INCREMENTAL, QUEUE_FULL
from .._runtime.memory import discard_pages
from .._runtime.threads import in_parallel
from ..elements.density import window_factors
from .expansion import Workspaces, centers_within, with_room
from .params import ASSIGNMENTS, check_choice

_k = native.of("expand")  # the compiled expansion kernels


def classify_exact(*args):
    """The compiled ``classify_exact``."""
    return native.kernel("exact.classify_exact")(*args)


def reclassify_exact(*args):
    """The compiled ``reclassify_exact``."""
    return native.kernel("exact.reclassify_exact")(*args)

__all__ = ["Classifier", "BoundedReplay", "Bounded", "Exact", "make_classifier"]

_ARENA = 5.0  # initial room of the record arena, entries per element
_RESERVE = 8.0  # arena allocated up front, entries per element (untouched pages cost nothing)
_SLACK = 0.05  # room added beyond the need when the arena's room is raised
_PARALLEL_MIN_WORK = 200_000  # recorded elements per pass worth a second thread
_MERGE_COST = 0.02  # merging a record against expanding it (measured: 2.5 against 146 ns)
_INCREMENTAL = 8  # labels updated in place when at most 1 center in 8 moved
_INCREMENTAL_SHARE = 0.5  # ... and the records to merge again are at most this share
_DISCARD_MIN = 1 << 16  # elements from which the arena's pages past its end are discarded


class Classifier:
    """One classification per call of :meth:`classify`, on a fixed weighted graph.

    Parameters
    ----------
    graph : ElementGraph
    weights : (2 e,) float64 ndarray
        Weight of each CSR entry of ``graph``.
    window_r2 : float
        Squared window radius ``(window * r)^2`` of the bounded expansions
        (times :func:`superfacets.elements.density.window_factors` of the center's
        element where ``graph.scale2`` is set: content-sensitive runs).
    spaces : Workspaces
        Work buffers and threads, shared with the initialization.
    """

    def __init__(self, graph, weights: np.ndarray, window_r2: float, spaces: Workspaces):
        self.m = graph.n_elements
        self.indptr, self.indices = graph.indptr, graph.indices
        self.c = np.ascontiguousarray(graph.positions)
        self.w = weights
        self.window_r2 = float(window_r2)
        # content-sensitive runs: a center's window scaled as its superfacet's extent
        self.wscale = window_factors(graph)
        self.spaces = spaces

    def classify(self, centers: np.ndarray, n_centers: int, dist: np.ndarray,
                 label: np.ndarray) -> tuple[int, int]:
        """Label every element (``label``, int32) and its distance (``dist``).

        ``centers[:n_centers]`` are the centers (label ``s`` for
        ``centers[s]``); orphan centers are appended to ``centers``.

        Returns
        -------
        (K, n_expansions) : (int, int)
            Centers now in use, and the expansions run.
        """
        raise NotImplementedError

    def forget_records(self) -> None:
        """Let go of what is kept between passes to save work (the same labels after)."""


class Bounded(Classifier):
    """The paper's bounded classification, every center expanded every pass."""

    def classify(self, centers, n_centers, dist, label):
        spaces = self.spaces
        k = with_room(spaces.get(0), lambda ws: _k.classify_bounded(
            self.indptr, self.indices, self.w, self.c, centers, n_centers, self.window_r2,
            dist, label, ws.local, ws.queue, spaces.inv_width, ws.vis, self.wscale))
        return k, k


class Exact(Classifier):
    """Exact nearest-center classification: one multi-source search, no window.

    Every element goes to the center at the smallest distance along the
    graph; ties go to the center listed first, whatever order the search
    settles elements in (``(distance, center)`` pairs compared
    lexicographically). Compiled, by blocks of elements on threads (the same fixed
    point as one search over the bounded expansions' bucket queue). From the second
    pass on, only the cells of the centers that moved are searched again
    (the compiled ``reclassify_exact``: the same labels and
    distances as a fresh search, bit for bit), where the call gets the same ``dist``
    and ``label`` arrays as the one before: they hold its result, which the next
    search starts from (the passes never write them between calls; other arrays start
    a fresh search). No copy of them is kept.
    """

    def __init__(self, graph, weights, window_r2, spaces):
        super().__init__(graph, weights, window_r2, spaces)
        self.inv_width = spaces.inv_width
        self.head = np.full(spaces.n_buckets, -1, dtype=np.int64)
        self._pool(1 << 10)  # (the kernel grows its own node pool as it needs)
        self.prev = self.dist = self.label = None  # the previous call's (the caller's arrays)
        self.first = np.full(self.m, -1, dtype=np.int32 if self.m < 2**31 - 1 else np.int64)
        self.mark = np.zeros(self.m, dtype=np.bool_)

    def resume(self, centers: np.ndarray, dist: np.ndarray, label: np.ndarray) -> None:
        """Start from an earlier classification of the same graph and weights: ``label``
        and ``dist`` as :meth:`classify` left them for the list ``centers`` (elements, in
        its order). The next :meth:`classify` given these two arrays searches again only
        the cells of the centers its list does not share (the same labels and distances as
        a fresh search, bit for bit); where the shared centers are not in the same order
        in both lists, it searches afresh. (A tiled run's labels phase, from its refine
        round's last pass: :mod:`superfacets.scale.tiles.phases`.)"""
        self.prev = np.ascontiguousarray(centers, dtype=np.int64)
        self.dist, self.label = dist, label

    def _pool(self, cap: int) -> None:
        itype = np.int32 if self.m < 2**31 - 1 else np.int64
        self.queue = (np.empty(cap, dtype=itype), np.empty(cap),
                      np.empty(cap, dtype=np.int64), self.head)
        self.qlab = np.empty(cap, dtype=itype)

    def classify(self, centers, n_centers, dist, label):
        # the arrays of the previous call hold its labels and distances (the passes never
        # write them between calls): given again, only the cells of the centers that moved
        # are searched again; other arrays start a fresh search (the same result)
        k = NOT_INCREMENTAL
        if self.prev is not None and self.label is label and self.dist is dist:
            k = reclassify_exact(self.indptr, self.indices, self.w, centers, n_centers, dist,
                                 label, self.queue, self.qlab, self.inv_width, self.prev,
                                 self.first, self.mark)
            if k == QUEUE_FULL:  # the previous result is spoilt: from scratch, more room
                self._pool(2 * self.queue[0].shape[0])
                k = NOT_INCREMENTAL
        self.dist, self.label = dist, label
        while k < 0:
            k = classify_exact(
                self.indptr, self.indices, self.w, centers, n_centers, dist, label,
                self.queue, self.qlab, self.inv_width)
            if k < 0:
                self._pool(2 * self.queue[0].shape[0])
        self.prev = centers[:k].copy()
        return k, 0


def make_classifier(assignment: str, graph, weights: np.ndarray, window_r2: float,
                    spaces: Workspaces, *, replay: bool = True) -> Classifier:
    """The classifier of ``assignment`` (``'bounded'`` or ``'exact'``).

    ``replay=False`` gives the plain :class:`Bounded` instead of
    :class:`BoundedReplay` (same labels, every center expanded every pass).

    Raises
    ------
    ParameterError
        On an unknown ``assignment``.
    """
    check_choice("assignment", assignment, ASSIGNMENTS)
    if assignment == "exact":
        return Exact(graph, weights, window_r2, spaces)
    return (BoundedReplay if replay else Bounded)(graph, weights, window_r2, spaces)


class BoundedReplay(Classifier):
    """The paper's bounded classification, replaying the expansions of centers that did not move.

    The previous pass's expansions are kept in one arena (``face`` int32, ``dist``
    float64, one entry per settled element; ``start`` / ``len`` per center). A center
    that was a center in the previous pass reuses its record; the others are expanded
    (on up to ``n_threads`` threads). Records merge by the lexicographic (distance,
    center index) rule, in any order; then orphans are seeded. The arena is compacted
    (records of moved centers dropped) when its free end runs short, its room raised
    within ``8 n`` entries allocated up front (pages cost memory once written): about
    ``12 * 5`` bytes per element written (each lies in about 4.4 windows, ``window = 2``).
    """

    def __init__(self, graph, weights: np.ndarray, window_r2: float, spaces: Workspaces):
        super().__init__(graph, weights, window_r2, spaces)
        m = self.m
        self.limit = int(_ARENA * m) + 1024  # room in use: records lie in [0, limit)
        self.high = 0  # the part of the arena written so far
        cap = int(_RESERVE * m) + 1024
        self.face = np.empty(cap, dtype=np.int32)
        self.dist = np.empty(cap)
        self.end = 0
        self.prev_centers = np.empty(0, dtype=np.int64)
        self.prev_order = self.prev_sorted = np.empty(0, dtype=np.int64)
        self.prev_start = np.empty(0, dtype=np.int64)
        self.prev_len = np.empty(0, dtype=np.int64)

    def forget_records(self) -> None:
        """Let the kept expansions go (about 60 bytes per element): the next pass expands
        every center, the same labels as replaying them (before the swaps on large graphs)."""
        self.face, self.dist = np.empty_like(self.face), np.empty_like(self.dist)  # untouched
        self.end = self.high = 0
        self.limit = int(_ARENA * self.m) + 1024
        self.prev_centers = self.prev_order = self.prev_sorted = np.empty(0, dtype=np.int64)
        self.prev_start = self.prev_len = np.empty(0, dtype=np.int64)
        self.left = None

    # -- arena -------------------------------------------------------------
    def _make_room(self, need: int, start: np.ndarray, length: np.ndarray) -> None:
        """Free ``need`` entries at the end, keeping the segments ``start``/``length``
        (``start`` updated in place).

        Dropped records are compacted away before the room is raised, and before
        writing past the part of the arena written so far (``high``) where they
        are worth a copy, so that part (its resident memory) stays within a few
        percent of the largest set of records one pass needs.
        """
        holes = self.end - int(length.sum())
        if self.limit - self.end >= need and (self.end + need <= self.high
                                              or holes < _SLACK * self.end):
            return
        self.end = int(_k.compact_records(np.argsort(start, kind="stable"), start,
                                                 length, self.face, self.dist))
        if self.limit - self.end >= need:
            return
        self._grow(need - (self.limit - self.end) + int(_SLACK * (self.end + need)) + 1024)

    def _grow(self, extra: int) -> None:
        """Raise the room by ``extra`` entries, keeping ``[0, end)``: within the
        reserved arena for free, else into a larger one (copied)."""
        self.limit += max(int(extra), 1024)
        if self.limit <= self.face.shape[0]:
            return
        cap = max(self.limit, int(1.5 * self.face.shape[0]))
        face = np.empty(cap, dtype=np.int32)
        dist = np.empty(cap)
        face[:self.end] = self.face[:self.end]
        dist[:self.end] = self.dist[:self.end]
        self.face, self.dist = face, dist

    def classify(self, centers, n_centers, dist, label):
        indptr, indices, w, c, window_r2 = self.indptr, self.indices, self.w, self.c, self.window_r2
        spaces = self.spaces
        cs = centers[:n_centers]
        # index of each center among the previous ones (-1: none), from the sorted list
        pos = np.minimum(np.searchsorted(self.prev_sorted, cs), self.prev_sorted.shape[0] - 1)
        idx = np.where(self.prev_sorted[pos] == cs, self.prev_order[pos], -1) \
            if self.prev_sorted.shape[0] else np.full(cs.shape[0], -1)
        reuse = idx >= 0
        seg_start = np.empty(self.m + 1, dtype=np.int64)  # per center (orphans appended)
        seg_len = np.empty(self.m + 1, dtype=np.int64)
        kept = np.flatnonzero(reuse)
        todo = np.flatnonzero(~reuse)
        base = self._unset_moved(cs, idx, kept, todo, dist, label)
        seg_start[kept] = self.prev_start[idx[kept]]
        seg_len[kept] = self.prev_len[idx[kept]]
        if base is None:
            base = kept
        if self.prev_len.shape[0]:
            expected = int(1.1 * todo.shape[0] * self.prev_len.mean())
        else:  # first pass: each face lies in about 4.4 windows
            expected = int(0.9 * self.limit)
        # room for the new expansions, keeping only the records reused now
        while True:
            ks = seg_start[kept]
            self._make_room(expected + 4096, ks, seg_len[kept])
            seg_start[kept] = ks
            st = self._expand_and_merge(indptr, indices, w, c, cs, window_r2, seg_start,
                                        seg_len, base, todo, expected, dist, label,
                                        base is not kept)
            if st >= 0:
                break
            # a thread ran out of room (its share, in proportion to its centers, was short
            # of its records): redo with all the room there is, or twice what was tried
            # where that is no more; (twice the free room each time grew the arena
            # twofold every pass of a run whose centers' windows differ widely in size)
            room = int((self.limit - self.end) / 1.25) - 4096
            expected = room if room > expected else 2 * expected
        new_end = st
        # orphans (sequential: they depend on the labels)
        ws = spaces.get(0)
        while True:
            p, k = _k.seed_orphans(
                indptr, indices, w, c, centers, n_centers, window_r2, dist, label, ws.local,
                ws.queue, spaces.inv_width, self.face, self.dist, new_end, self.limit,
                seg_start, seg_len, self.wscale)
            if p >= 0:
                break
            # undo the orphans' labels: merge everything again, then retry with more room
            if p == QUEUE_FULL:
                ws.grow(p)
            else:
                self.end = new_end
                self._grow(self.limit // 2)
            self._merge_only(n_centers, seg_start, seg_len, dist, label)
        self.end = int(p)
        self.high = max(self.high, self.end)
        if self.m >= _DISCARD_MIN:  # (records moved down: what lies past the end is dead)
            discard_pages(self.face[self.end:]), discard_pages(self.dist[self.end:])
        # this pass's records become the previous ones
        self.prev_centers = centers[:k].copy()
        self.prev_order = np.argsort(self.prev_centers, kind="stable")
        self.prev_sorted = self.prev_centers[self.prev_order]
        self.prev_start = seg_start[:k].copy()
        self.prev_len = seg_len[:k].copy()
        self.left = (dist, label)
        return k, int(todo.shape[0]) + (k - n_centers)

    def _unset_moved(self, cs, idx, kept, todo, dist, label):
        """Where the previous pass's labels can be updated in place, unlabel the faces
        of the centers that moved and return the reused centers whose records may reach
        them (to be merged again); else None (every record is merged afresh).

        In place when ``dist``/``label`` are the arrays this classifier left, every
        reused center keeps its index, and few moved: a face keeps its ``(dist, label)``
        unless its center moved; those faces get the least over the records of the
        reused centers whose windows meet the moved one's (by the triangle inequality,
        every record that reaches them) and the new records: the labels of merging all.
        """
        left = getattr(self, "left", None)
        n, n_moved = cs.shape[0], todo.shape[0]
        if (left is None or left[0] is not dist or left[1] is not label
                or n != self.prev_centers.shape[0] or n_moved * _INCREMENTAL > n
                or not np.array_equal(idx[kept], kept)):
            return None
        if n_moved == 0:
            return kept[:0]
        c = self.c
        old, now = self.prev_centers[todo], cs[kept]
        if now.shape[0] == 0:
            return None
        scale = self.wscale  # window radii: each center's (content-sensitive runs)
        r_old = np.sqrt(self.window_r2 * (scale[old] if scale.shape[0] else np.ones(n_moved)))
        r_max = np.sqrt(self.window_r2 * (float(scale[now].max()) if scale.shape[0] else 1.0))
        near = centers_within(c[old], r_old + r_max, c[now])
        if near is None:
            return None
        lengths = self.prev_len[kept]
        if lengths[near].sum() > _INCREMENTAL_SHARE * lengths.sum():
            return None
        _k.unset_owned(todo, self.prev_start, self.prev_len, self.face, dist, label)
        return kept[near]

    def _merge_only(self, n_centers, seg_start, seg_len, dist, label) -> None:
        _k.reset_labels(dist, label)
        _k.merge_some(np.arange(n_centers), seg_start, seg_len, self.face, self.dist,
                            dist, label)

    def _expand_and_merge(self, indptr, indices, w, c, cs, window_r2, seg_start, seg_len,
                          kept, todo, expected, dist, label, in_place=False):
        """Expand the centers ``todo`` into the free end of the arena and merge
        every record (those of ``kept`` and the new ones) into ``dist``/``label``
        (reset first, unless ``in_place``).

        Thread 0 merges the reused records and expands its share of ``todo``,
        merging each new record while it is in cache; the other threads expand
        their shares into their own parts of the arena (records only), merged by
        thread 0 once they are done. Only the caller's ``dist``/``label`` exist
        (merging costs about 2 % of expanding, per record). Returns the new end
        of the arena, or -1 if a thread ran out of room (nothing is kept).
        """
        spaces = self.spaces
        n = todo.shape[0]
        # the room the expected records need, and a quarter more (a thread that runs
        # out redoes the pass with more): pages beyond it stay untouched
        lo, hi = self.end, min(self.limit, self.end + int(1.25 * expected) + 4096)
        n_thr = spaces.n_threads
        if n_thr <= 1 or expected + int(seg_len[kept].sum()) < _PARALLEL_MIN_WORK:
            n_thr = 1
        if n_thr == 1:
            parts = [todo]
        else:  # thread 0 takes fewer, for its merging; each thread a run of the centers
            # by element (a spatial order: points in Z-order, faces as meshed)
            per = expected / max(n, 1)  # records per expansion
            merging = _MERGE_COST * (int(seg_len[kept].sum()) + expected) / max(per, 1.0)
            n0 = int(max(0.0, min(n, (n - (n_thr - 1) * merging) / n_thr)))
            by_element = todo[np.argsort(cs[todo], kind="stable")]
            parts = [by_element[:n0]] + np.array_split(by_element[n0:], n_thr - 1)
        # the free room shared in proportion to the expansions each thread runs
        share = np.cumsum([0] + [p.shape[0] for p in parts]) / max(n, 1)
        bounds = [lo + int((hi - lo) * x) for x in share[:-1]] + [hi]
        none_d, none_l = np.empty(0), np.empty(0, dtype=np.int32)

        def run(t):
            ws = spaces.get(t)
            part = np.ascontiguousarray(parts[t])  # (the compiled kernels: contiguous)
            srcs_t = np.ascontiguousarray(cs[part])
            os_t = np.empty(part.shape[0], dtype=np.int64)
            ol_t = np.empty(part.shape[0], dtype=np.int64)
            while True:
                if t == 0:
                    if not in_place:
                        _k.reset_labels(dist, label)
                    _k.merge_some(kept, seg_start, seg_len, self.face, self.dist, dist, label)
                p = _k.expand_many(indptr, indices, w, c, srcs_t, part, window_r2, ws.local,
                                   ws.queue, spaces.inv_width, self.face, self.dist, bounds[t],
                                   bounds[t + 1], os_t, ol_t,
                                   *((dist, label) if t == 0 else (none_d, none_l)),
                                   self.wscale)
                if p != QUEUE_FULL:
                    break
                ws.grow(p)
            seg_start[part] = os_t
            seg_len[part] = ol_t
            return p

        ends = in_parallel(run, n_thr)
        if min(ends) < 0:
            return -1
        for t in range(1, n_thr):
            _k.merge_some(np.ascontiguousarray(parts[t]), seg_start, seg_len, self.face,
                          self.dist, dist, label)
        # close the gaps between the threads' ranges
        pos = ends[0]
        for t in range(1, n_thr):
            a, b = bounds[t], ends[t]
            if a != pos:
                self.face[pos:pos + b - a] = self.face[a:b]
                self.dist[pos:pos + b - a] = self.dist[a:b]
                seg_start[parts[t]] -= a - pos
            pos += b - a
        return pos
