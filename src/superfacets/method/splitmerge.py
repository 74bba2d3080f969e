"""Split-and-merge swaps: move superfacets off the creases they straddle, keeping K.

The paper's iteration converges to a local optimum in which some
superfacets straddle a concave crease while two neighbours elsewhere cover
one smooth patch between them. A *swap* splits the first in two and merges
the other two, so the number of superfacets stays the same; the iteration
then runs again from the new centers. Swaps are chosen by an energy of the
paper's own distances (``docs/notes/method.md``, section 3.1): for a superfacet
``S`` with center ``c`` (the element nearest its size-weighted mean),

    E(S) = sum over f in S of size_f * d_S(c, f) ** power,

with ``d_S`` the face-graph distance of the paper's weights (eqs. 1-3)
restricted to ``S``. A crossing of a concave crease is long in that distance
(alpha), so a superfacet straddling one has a high energy, and a high
``power`` (4: between the k-means energy, 2, and the farthest element alone)
makes the far side count most. The split of ``S`` is a 2-means of its
elements in ``d_S`` (seeds: the farthest element and the one farthest from
it; three re-centerings); its *gain* is ``E(S) - E(S_1) - E(S_2)``. The *loss*
of merging two adjacent superfacets is ``E(S u T) - E(S) - E(T)``. Swaps are
taken greedily, the largest gain with the smallest loss, while the gain
exceeds the loss and ``min_gain`` times the mean energy of a superfacet, and
no superfacet is in two swaps, at most ``max_fraction * K`` a round.

Only the candidates that can decide a swap are evaluated in full, with the
same swaps as evaluating all: a split's gain is at most its superfacet's
energy, so the 2-means run lazily, highest energy first, until the greedy
choice is decided; a merge's search stops as soon as the union's energy
exceeds the largest gain (that merge can never be taken), and a union that
leaves the window is never searched. Not in the paper (its authors call a clean-up
"a priority next step"); judged in ``docs/notes/cleanup.md``.
"""

from __future__ import annotations

import numpy as np

from .._kernels import native
from .._runtime.memory import give_back_free_memory
from .._runtime.threads import in_parallel
from ..elements.kinds import kind_of
from ..elements.labels import relabel_dense
from . import passes
from .passes import hold_small_moves, update_centers

__all__ = ["swap_round", "swap_and_iterate", "POWER", "LLOYD",
           "MAX_FRACTION", "MIN_GAIN", "ROUNDS", "START_TOL", "FAST_ROUNDS", "PASSES_AFTER",
           "SWAP_ETA_CONVEX_FACES", "HOLD_AFTER_FACES", "PASSES_AFTER_FACES",
           "FORGET_MIN"]

# the compiled kernels (module-level names: tests patch them)
energies, split_candidates, merge_energies, label_pairs = (
    (lambda *a, _n=n: native.kernel(f"splitmerge.{_n}")(*a))
    for n in ("energies", "split_candidates", "merge_energies", "label_pairs"))

#: Exponent of the distances in the energy.
POWER = 4.0
#: Re-centerings of the 2-means of a split.
LLOYD = 3
#: Swaps per round at most, as a fraction of the superfacets.
MAX_FRACTION = 0.3
#: Rounds of (swaps, then the iteration again) at most, where the passes run to the
#: paper's rule (``tol = 0``).
ROUNDS = 3
#: With a tolerance (``tol > 0``, the default) the swaps come early and the passes after
#: them are few: the passes stop for the swaps once one changes the superfacet of at most
#: this fraction of the area (the swaps then move whole superfacets, and the passes before
#: the first ones are the costly ones: every center expanded) ...
START_TOL = 0.2
#: ... one round of swaps ...
FAST_ROUNDS = 1
#: ... then at most this many passes, and the clean-up, if on, finishes the boundaries
#: (docs/notes/cleanup.md, "Split-and-merge at the paper's speed"). Vertices keep 2:
#: one pass raised their error.
PASSES_AFTER = kind_of("vertices").passes_after  # values: the table of kinds
#: The same on faces: 1. With the swap energies of :data:`SWAP_ETA_CONVEX_FACES` the
#: second pass no longer pays: on the 300 meshes, k = 50 ... 300, UE within 0.4 points of
#: two passes', compactness the same to 0.1 point, about 5 % of a run's time
#: (docs/notes/cleanup.md, "One pass after the swaps").
PASSES_AFTER_FACES = kind_of("faces").passes_after
#: Factor of ``eta_convex`` in the weights of the swap energies on faces: 0.5 counts a
#: convex fold half as much as the passes do, so a superfacet wrapped round a thin convex
#: tube (a glasses frame of few faces around) no longer reads as straddling a crease,
#: while a cup's rim still does. On the 300 benchmark meshes, k = 50 ... 300: UE 1.2-2.6
#: points further below the paper's, compactness 0.4-0.6 points; 0 (concave creases
#: alone, the minima rule) gains more UE but raises Cup's by 11 % at k = 50
#: (docs/notes/cleanup.md, "Swap energies"). On vertices (neighbourhood-averaged normals) 0
#: raised the UE: they keep the run's weights (1).
SWAP_ETA_CONVEX_FACES = kind_of("faces").swap_eta_convex
#: On faces, the passes after the swaps keep in place a center that moves by less than
#: this many times ``center_tol * r`` (its window's expansion is replayed, not run again):
#: about 4 % of a run's time, the same quality (docs/notes/cleanup.md, "Swap energies").
HOLD_AFTER_FACES = kind_of("faces").hold_after
#: A swap is taken only if its split lowers the energy by at least this many times the
#: mean energy of a superfacet (the total over K): a split that removes less than an
#: average superfacet holds fixes no crease, and its swap mostly reshuffles a smooth
#: region (a cup's body). On the 300 benchmark meshes, k = 50 ... 300: every category
#: below the paper on UE and compactness at every k, and fewer swaps to run
#: (docs/notes/cleanup.md, "The smallest swaps").
MIN_GAIN = 1.0
#: Elements from which the passes' kept expansions (about 60 bytes per element) go before
#: the swaps; the pass after them expands every center (same labels; 1.7M faces: +0.7 s).
FORGET_MIN = 1 << 22


def swap_round(graph, weights: np.ndarray, labels: np.ndarray, *, window_r2: float = np.inf,
               power: float = POWER, lloyd: int = LLOYD, max_fraction: float = MAX_FRACTION,
               n_threads: int = 1, pruned: bool = True,
               min_gain: float = MIN_GAIN, frozen: np.ndarray | None = None
               ) -> tuple[np.ndarray, int]:
    """One round of K-preserving swaps (see the module notes).

    Parameters
    ----------
    graph : ElementGraph
    weights : (2 e,) float64 ndarray
        Weight of each CSR entry of ``graph`` (the paper's, eqs. 1-3).
    labels : (n,) int ndarray
        Dense labels ``0..K-1``.
    window_r2 : float, default inf
        Squared window radius ``(window * r) ** 2`` of the classification:
        two superfacets merge only if every element of the union lies within
        it of the union's center (a larger union would leave elements that
        no window reaches, seeding new superfacets in the passes that follow).
    power : float, default 4
        Exponent of the distances in the energy (``> 0``).
    lloyd : int, default 3
        Re-centerings of each split's 2-means.
    max_fraction : float, default 0.3
        Swaps at most, as a fraction of ``K``.
    n_threads : int, default 1
        Threads evaluating the splits and merges (each candidate on its own:
        the same result for any number).
    pruned : bool, default True
        Evaluate only the candidates that can decide a swap (the same swaps):
        a split's gain is at most its superfacet's energy, so splits are
        evaluated lazily, the highest energies first, only until the greedy
        choice is decided; a merge's search is abandoned once its energy
        exceeds the largest gain of any split. ``False`` evaluates every
        candidate in full (the reference the tests compare with).
    frozen : (K,) bool ndarray, optional
        Superfacets that take no part in a swap (neither split nor merged: a tile's
        halo, whose superfacets their own tiles move).

    Returns
    -------
    labels : (n,) int32 ndarray
        The labels after the swaps, ``0..K-1``, every label still used (a
        split's second part takes the label of the superfacet merged away).
    n_swaps : int

    Examples
    --------
    >>> from superfacets.method.weights import csr_weights, edge_weights
    >>> sphere = trimesh.creation.icosphere(subdivisions=3)
    >>> m = Mesh(sphere.vertices, sphere.faces)
    >>> r = segment(m, 20)
    >>> g = face_graph(m)
    >>> w = csr_weights(g, edge_weights(g, "paper", alpha=200, eta_convex=0.2))
    >>> new, n = swap_round(g, w, r.labels)
    >>> int(new.max()) + 1 == int(r.labels.max()) + 1
    True
    """
    g = graph
    n = g.n_elements
    lab = np.ascontiguousarray(labels, dtype=np.int32)
    k = int(lab.max()) + 1
    members, bounds = _members(lab, k)
    sizes = np.ascontiguousarray(g.sizes, dtype=np.float64)
    positions = np.ascontiguousarray(g.positions, dtype=np.float64)
    # heap room: the CSR entries of the two superfacets with the most of them, plus one
    entries = np.sort(np.bincount(lab, weights=np.diff(g.indptr), minlength=k))
    heap = int(entries[-2:].sum()) + 1
    n_thr = max(1, min(int(n_threads), k))
    largest = int(np.sort(np.diff(bounds))[-2:].sum())  # work lists: a split, or a union
    space = [(np.empty(heap), np.empty(heap, dtype=np.int64), np.empty(largest, dtype=np.int64))
             for _ in range(n_thr)]
    dist, dist2 = np.empty(n), np.empty(n)
    stamp = np.full(n, -1, dtype=np.int64)
    stamp2 = np.full(n, -1, dtype=np.int64)
    energy, far, split_energy = np.empty(k), np.empty(k, dtype=np.int64), np.full(k, np.inf)
    second = np.zeros(n, dtype=np.bool_)
    calls = iter(range(1, 1 << 22))  # search ids of a kernel call: from call * 2**40 on
    args = (g.indptr, g.indices, weights, lab, members, bounds, sizes, positions, float(power))
    # energies of superfacets t, t + n_thr, ... on thread t: disjoint, shared arrays
    bases = [next(calls) << 40 for _ in range(n_thr)]
    in_parallel(lambda t: energies(*args, energy, far, dist, stamp, bases[t],
                                   *space[t][:2], t, n_thr), n_thr)

    def evaluate(which):  # the splits of superfacets ``which``
        which = np.asarray(which, dtype=np.int64)
        b = [next(calls) << 40 for _ in range(n_thr)]
        in_parallel(lambda t: split_candidates(
            *args, int(lloyd), which, far, split_energy, second, dist, dist2, stamp,
            stamp2, b[t], *space[t], t, n_thr), n_thr)

    # (a frozen superfacet's split gains nothing: never chosen, and evaluated last)
    splits = _SplitOrder(energy if frozen is None else np.where(frozen, 0.0, energy),
                         split_energy, evaluate, 8 * n_thr, pruned)
    limit = max(1, int(max_fraction * k))
    best = splits.peek()
    if best is None:  # no split lowers the energy: no swap
        return lab.copy(), 0
    # adjacent superfacets: each pair once, a < b
    key = label_pairs(g.indptr, g.indices, lab, np.int64(k))  # (no pairs rebuilt)
    pa, pb = key // k, key % k
    union = np.empty(key.shape[0])
    most = best[1] if pruned else np.inf
    # unions overlap: each thread its own distances and stamps, kept by slot within the
    # union (an element at its place among its superfacet's members, the second's after
    # the first's): the size of the largest union, not of the input, on each thread
    rank = _ranks(members, bounds, lab)
    own = [(np.empty(largest), np.full(largest, -1, dtype=np.int64)) for _ in range(n_thr)]
    mb = [next(calls) << 40 for _ in range(n_thr)]
    in_parallel(lambda t: merge_energies(
        *args, pa, pb, energy, float(window_r2), float(most), union, *own[t], rank, mb[t],
        *space[t], t, n_thr), n_thr)
    loss = union - energy[pa] - energy[pb]  # inf: not allowed, or beyond any gain
    if frozen is not None:
        loss[frozen[pa] | frozen[pb]] = np.inf

    remap, split_to, n_swaps = _greedy_swaps(splits, pa, pb, loss, k, limit,
                                             min_gain * float(np.mean(energy)))
    splits = own = space = rank = dist = dist2 = stamp = stamp2 = members = None  # noqa: F841
    out = remap[lab]
    moved = second & (split_to[lab] >= 0)
    out[moved] = split_to[lab[moved]]
    return out, n_swaps


def _greedy_swaps(splits, pa, pb, loss, k: int, limit: int, least_gain: float):
    """The swaps chosen greedily, at most ``limit``: the largest gains (splits, taken from
    ``splits`` largest first, down to ``least_gain``) with the smallest losses (merges of
    the adjacent pairs ``pa``, ``pb``), each superfacet in one swap. Returns the label of
    each label after the merges, the label the second part of each split takes (-1: not
    split) and the number of swaps."""
    merges = np.lexsort((pb, pa, loss))
    used = np.zeros(k, dtype=bool)
    remap = np.arange(k, dtype=np.int32)
    split_to = np.full(k, -1, dtype=np.int32)
    j = n_swaps = 0
    for _ in range(limit):
        nxt = splits.pop()
        if nxt is None:
            break
        s, gain = nxt
        if gain < least_gain:  # the gains come largest first
            break
        if used[s]:
            continue
        while j < merges.shape[0] and (used[pa[merges[j]]] or used[pb[merges[j]]]
                                       or s in (pa[merges[j]], pb[merges[j]])):
            j += 1
        if j >= merges.shape[0] or loss[merges[j]] >= gain:
            break
        u, v = int(pa[merges[j]]), int(pb[merges[j]])
        j += 1
        remap[v] = u  # v merges into u; its label goes to the second part of s
        split_to[s] = v
        used[[s, u, v]] = True
        n_swaps += 1
    return remap, split_to, n_swaps


def _ranks(members: np.ndarray, bounds: np.ndarray, lab: np.ndarray) -> np.ndarray:
    """Each element's place among its superfacet's members (:func:`_members`), made by
    blocks (no temporary of one entry per element)."""
    n, block = members.shape[0], 1 << 20
    rank = np.empty(n, dtype=np.int64)
    for a in range(0, n, block):
        part = members[a:a + block]
        rank[part] = np.arange(a, a + part.shape[0], dtype=np.int64) - bounds[lab[part]]
    return rank


def _members(lab: np.ndarray, k: int) -> tuple[np.ndarray, np.ndarray]:
    """The elements of each superfacet, ascending: ``members[bounds[s]:bounds[s + 1]]``
    (a stable counting sort of ``lab``, the order of ``np.argsort(lab, kind="stable")``)."""
    count_keys = native.kernel("adjacency.count_keys")
    scatter_keys = native.kernel("adjacency.scatter_keys")

    n = lab.shape[0]
    keep = np.zeros(n, dtype=np.bool_)  # nothing skipped
    counts = np.zeros(k, dtype=np.int64)
    count_keys(lab, keep, 0, n, counts)
    bounds = np.zeros(k + 1, dtype=np.int64)
    np.cumsum(counts, out=bounds[1:])
    members = np.empty(n, dtype=np.int64)
    scatter_keys(lab, keep, 0, n, bounds[:-1].copy(), members)
    return members, bounds


class _SplitOrder:
    """The superfacets with a positive split gain, by gain descending (then
    index), each split evaluated only when it may come next: a superfacet's
    energy bounds its gain (the parts' energies are >= 0), so while an
    unevaluated bound leads the queue, the ``batch`` leading bounds are
    evaluated (``evaluate(which)`` fills ``split_energy``). ``pruned=False``
    evaluates all at once."""

    def __init__(self, energy, split_energy, evaluate, batch: int, pruned: bool):
        import heapq

        self.heapq, self.energy, self.split_energy = heapq, energy, split_energy
        self.evaluate, self.batch = evaluate, batch
        k = energy.shape[0]
        if pruned:
            self.queue = [(-float(energy[s]), s, False) for s in range(k)]
        else:
            evaluate(np.arange(k))
            self.queue = [(-self._gain(s), s, True) for s in range(k)]
        heapq.heapify(self.queue)

    def _gain(self, s: int) -> float:
        return float(self.energy[s] - self.split_energy[s])

    def peek(self):
        """``(s, gain)`` of the next split, or None when no gain is left."""
        q, hq = self.queue, self.heapq
        while q and not q[0][2]:
            if -q[0][0] <= 0:  # bounds <= 0: no gain left
                return None
            top = [hq.heappop(q) for _ in range(min(self.batch, len(q)))]
            todo = [s for _, s, exact in top if not exact]
            self.evaluate(todo)
            for item in top:
                hq.heappush(q, item if item[2] else (-self._gain(item[1]), item[1], True))
        if not q or -q[0][0] <= 0:
            return None
        return q[0][1], -q[0][0]

    def pop(self):
        """Remove and return :meth:`peek`."""
        nxt = self.peek()
        if nxt is not None:
            self.heapq.heappop(self.queue)
        return nxt


def swap_and_iterate(it, graph, weights: np.ndarray, classifier, centers: np.ndarray,
                     sizes: np.ndarray, positions: np.ndarray, max_iter: int, *,
                     rounds: int = ROUNDS, window_r2: float = np.inf, min_move: float = 0.0,
                     n_threads: int = 1, passes_after: int | None = None,
                     swap_weights: np.ndarray | None = None, hold_after: float = 1.0,
                     fixed: np.ndarray | None = None, **iterate_kw):
    """Up to ``rounds`` rounds of (:func:`swap_round`, then the passes again from
    the new centers), after the iteration ``it`` (an
    :class:`~superfacets.method.passes.Iteration`); stops at a round without a swap.
    A round whose passes end with another number of superfacets than before
    it (elements no window reached seed new ones, or a superfacet is left
    empty) is undone, and the rounds stop: the number never changes.

    The new centers are the paper's update of the swapped labels (the
    element nearest each superfacet's mean; a center that would move by less
    than ``min_move`` stays, so the expansions of untouched superfacets are
    replayed). ``centers`` is the work array of :func:`~superfacets.method.passes.iterate`;
    ``iterate_kw`` goes to it. ``passes_after`` bounds the passes after each
    round (default: ``max_iter``); passes stopped by that bound count as
    converged (the schedule's end, not ``max_iter``). ``swap_weights`` are
    the weights of the swap energies (default: ``weights``, those of the
    passes; the pipeline gives :func:`~superfacets.method.weights.convex_scaled`
    with the kind's ``swap_eta_convex``). In the passes after
    a round a center moving by less than ``hold_after * min_move`` stays. The centers
    on ``fixed`` elements ((n,) bool) stay, and their superfacets are not swapped.

    Returns
    -------
    it : Iteration
        The last iteration, with ``n_iter``, ``n_passes`` and ``expansions``
        summed over every run.
    n_swaps : int
        Swaps made over all rounds.
    """
    from dataclasses import replace

    def used(it) -> np.ndarray:
        present = np.zeros(it.centers.shape[0], dtype=bool)
        present[it.label] = True
        return present

    n_swaps, n_iter, n_passes, expansions = 0, it.n_iter, it.n_passes, it.expansions
    settled = it.settled
    for _ in range(rounds):
        present = used(it)
        old = it.centers[present]
        classifier.spaces.release()  # the expansions' buffers: not read by the swaps
        if graph.n_elements >= FORGET_MIN:  # nor the kept expansions (60 B per element),
            classifier.forget_records()  # nor what the threads' kernels freed (the
            give_back_free_memory()  # allocator keeps it per thread: tens of MiB each)
        # float32 weights widened for the round (the kernels add each to a float64
        # distance), once the expansions' records are let go (a large graph's peak)
        swap_w = np.asarray(weights if swap_weights is None else swap_weights,
                            dtype=np.float64)
        new, n = swap_round(graph, swap_w, relabel_dense(it.label).astype(np.int32),
                            window_r2=window_r2, n_threads=n_threads,
                            frozen=None if fixed is None else fixed[old])
        del swap_w
        if n == 0:
            break
        moved = update_centers(new, old.shape[0], sizes, positions, old)
        if min_move > 0:
            hold_small_moves(moved, old, positions, min_move)
        passes.hold_fixed(moved, old, fixed)
        moved = moved[moved >= 0]
        centers[:moved.shape[0]] = moved
        bound = max_iter if passes_after is None else min(max_iter, passes_after)
        after = passes.iterate(classifier, centers, moved.shape[0], sizes, positions, bound,
                        min_move=min_move * hold_after, fixed=fixed, **iterate_kw)
        if bound < max_iter and after.n_iter >= bound:  # the schedule's end, not max_iter
            after = replace(after, converged=True)
        n_iter += after.n_iter
        n_passes += after.n_passes
        expansions += after.expansions
        settled += after.settled
        if used(after).sum() != present.sum():
            break  # an orphan seeded a superfacet or one was emptied: keep the labels before
        it = after
        n_swaps += n
    return replace(it, n_iter=n_iter, n_passes=n_passes, expansions=expansions,
                   settled=settled), n_swaps
