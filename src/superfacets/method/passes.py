"""The iteration: passes of (classify, update) until no center moves or ``max_iter``.

Paper section 3.1, steps 2-3 (``docs/notes/method.md``, section 3). :func:`iterate`
runs the passes with any :class:`~superfacets.method.classify.Classifier`;
:func:`update_centers` is the center update; :func:`final_centers` names the
center of each superfacet of the final labels.

Cycle jump: the ordered center list of a pass determines every later pass,
so when it repeats the list of an earlier pass the run is periodic (the
flip-flopping that keeps many runs from converging). :func:`iterate` then
jumps to the center list that pass ``max_iter`` would have and classifies it
once: labels, centers, ``n_iter`` and the orphan count are those of running
every pass (tested against ``jump_cycles=False``).

Settling (``settle=True``, the rule on point clouds): a cycle is a flaw of the update,
not a place to stop. When the center list repeats, the run goes back to the pass of the
cycle whose classification had the lowest energy (each element's distance to its center
along the graph weighted by paper eq. 3, summed weighted by size) and holds where they
are the centers that moved during the cycle; the others go on until no center moves, and
the run has converged (a later cycle holds more). Centers oscillating out of phase keep
the whole list from ever repeating: a center the update sends back to one of its last
:data:`RECENT` places is held too (:class:`_Recent`). The centers held are counted in
:attr:`Iteration.settled`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .._kernels import native
from .._runtime.arrays import gather

__all__ = ["Iteration", "iterate", "update_centers", "hold_small_moves", "final_centers"]


def update_centers(label: np.ndarray, k: int, sizes: np.ndarray, positions: np.ndarray,
                   old_centers: np.ndarray) -> np.ndarray:
    """Center update (paper section 3.1, step 3).

    For each superfacet ``s < k``: the size-weighted mean of its element
    positions (plain mean if its size is zero), then its element nearest to
    that mean; the old center stays on ties, else the lowest index wins.

    Parameters
    ----------
    label : (n,) int32 ndarray
        Superfacet of each element, ``0..k-1``.
    k : int
    sizes : (n,) float64 ndarray
    positions : (n, 3) float64 ndarray
    old_centers : (k,) int64 ndarray
        Previous center of each superfacet, or -1.

    Returns
    -------
    (k,) int64 ndarray
        New center of each superfacet, -1 for an empty one.
    """
    new = np.empty(k, dtype=np.int64)
    native.kernel("update.update_centers")(label, k, sizes, positions, old_centers, new)
    return new


@dataclass
class Iteration:
    """Outcome of :func:`iterate`.

    Attributes
    ----------
    label : (n,) int32 ndarray
        Labels of the last classification, ``0..K-1`` (some maybe empty).
    centers : (K,) int64 ndarray
        The centers of the last classification (orphan centers included).
    n_iter : int
        Passes counted (those skipped by a cycle jump included).
    converged : bool
        True when the last update moved no center and seeded no orphan.
    n_orphan_seeds : int
        Orphan centers seeded over all passes.
    n_passes : int
        Classifications actually run.
    cycle_period : int
        0, or the period of the cycle of center lists that was jumped.
    expansions : int
        Expansions run by the classifier.
    changed : float
        Fraction of the area whose superfacet the last classification changed
        (-1 when not measured: ``tol = 0``, or the first pass).
    stopped_by_tol : bool
        True when the ``tol`` rule ended the run.
    settled : int
        Centers held where a cycle moved them (``settle=True``; 0 otherwise).
    dist : (n,) float64 ndarray or None
        Each element's distance to its center in the last classification (:func:`iterate`).
    classifier : Classifier or None
        The classifier of the passes, where the caller asked to keep it
        (:func:`~superfacets.method.stages.iterate_passes`: a tile's labels phase replays
        its recorded expansions); else None.
    """

    label: np.ndarray
    centers: np.ndarray
    n_iter: int
    converged: bool
    n_orphan_seeds: int
    n_passes: int
    cycle_period: int
    expansions: int
    changed: float = -1.0
    stopped_by_tol: bool = False
    settled: int = 0
    dist: np.ndarray | None = None
    classifier: object | None = None


def passes_done(bar, n_iter: int, max_iter: int, k_now: int, n_moved: int, changed: float,
                tol: float) -> None:
    """Advance the progress bar by one pass, and size it by the passes still to come: the
    movers' (and, with ``tol``, the changed share's) geometric decay over the passes so
    far, extrapolated to no mover (to ``tol``), at most ``max_iter`` (tqdm then shows a
    remaining time; a guess, renewed every pass).

    Examples
    --------
    >>> from tqdm import tqdm
    >>> bar = tqdm(total=None, disable=True)
    >>> for i, moved in enumerate((800, 400, 200), start=1):
    ...     passes_done(bar, i, 50, 100, moved, -1.0, 0.0)
    >>> bar.total  # 200 movers halving each pass: 9 more passes to fewer than one
    12
    """
    bar.update(1)
    history = bar.__dict__.setdefault("_superfacets_history", [])
    history.append((max(n_moved, 0), changed))
    left = _left(history, 0, 0.5)
    if tol > 0 and changed >= 0:
        left = min(left, _left(history, 1, tol))
    bar.total = min(max_iter, n_iter + left) if left < max_iter else None
    bar.set_postfix(centers=k_now, moved=n_moved)


def _left(history: list, column: int, target: float) -> int:
    """Passes until ``history``'s ``column`` decays to ``target``, at the rate of its last
    three passes; ``1 << 30`` where it does not decay."""
    values = [h[column] for h in history[-4:] if h[column] >= 0]
    if len(values) < 2 or values[-1] <= target:
        return 0 if values and values[-1] <= target else 1 << 30
    first, last = max(values[0], 1e-300), values[-1]
    rate = (last / first) ** (1.0 / (len(values) - 1))
    if not 0 < rate < 1:
        return 1 << 30
    return int(np.ceil(np.log(target / last) / np.log(rate)))


def iterate(classifier, centers: np.ndarray, n_centers: int, sizes: np.ndarray,
            positions: np.ndarray, max_iter: int, *, jump_cycles: bool = True,
            tol: float = 0.0, min_move: float = 0.0, bar=None,
            settle: bool = False, order: np.ndarray | None = None,
            fixed: np.ndarray | None = None) -> Iteration:
    """Alternate classification and center update (paper section 3.1).

    Parameters
    ----------
    classifier : Classifier
    centers : (n,) int64 ndarray
        Work array, ``centers[:n_centers]`` the initial centers.
    n_centers : int
    sizes : (n,) float64 ndarray
    positions : (n, 3) float64 ndarray
    max_iter : int
        Passes at most (``>= 1``).
    jump_cycles : bool, default True
        Jump over a cycle of center lists (see the module notes); same result.
    tol : float, default 0
        Also stop when a classification changed the superfacet of at most this
        fraction of the total size (area) against the previous one. 0: the
        paper's rule alone (stop when no center moves), bit for bit.
    min_move : float, default 0
        A center that the update would move by less than this (mesh units,
        between element positions; ``center_tol * r``) stays where it is
        (:func:`hold_small_moves`); the run has converged when no center moves
        further. 0: every move counts (the paper).
    bar : tqdm, optional
        Progress bar advanced once per pass (:func:`passes_done`).
    settle : bool, default False
        On a cycle of center lists, settle it (see the module notes) instead of
        jumping over it.
    order : (n,) int64 ndarray, optional
        A distinct key per element (a tile's: each element's row in the input): the
        centers of each pass listed by it, not by the superfacet they came from, so that
        the last classification's list is in that order (and its ties broken by it) where
        no orphan was seeded in it (a tiled run's labels phase resumes from it:
        :mod:`superfacets.scale.tiles.phases`). The same superfacets where no two centers
        reach an element at exactly the same distance.
    fixed : (n,) bool ndarray, optional
        Elements whose centers the update leaves where they are (a tile's refine round:
        its halo's centers, which their own tiles move; the tile's passes move only its
        core's, and the classifier keeps the cells of the centers that stay).

    Returns
    -------
    Iteration
    """
    m = positions.shape[0]
    dist = np.empty(m)
    label = np.empty(m, dtype=np.int32)  # one kernel specialization for all label arrays
    n_iter = n_orphans = n_passes = n_expanded = period = 0
    converged = by_tol = False
    changed = -1.0
    prev = None  # with tol: the previous labels, in this pass's superfacet indices
    total = float(sizes.sum()) if tol > 0 else 0.0
    seen: dict[bytes, int] = {}
    states: list[np.ndarray] = []
    orphans_per_pass: list[int] = []
    energies: list[float] = []
    held = np.zeros(m, dtype=bool) if settle else None  # elements whose center stays
    recent = _Recent() if settle else None
    while True:
        key = centers[:n_centers].tobytes()
        if settle and key in seen:  # back to the cycle's best pass, its movers held
            n_centers = _settle(centers, states, energies, seen.pop(key), held)
            seen, states, energies, orphans_per_pass = {}, [], [], []
            prev = None
            continue
        if jump_cycles and key in seen and not period and n_iter < max_iter - 1:
            j = seen[key]  # pass j (0-based) had the same centers as pass n_iter
            period = n_iter - j
            last = max_iter - 1
            n_orphans += sum(orphans_per_pass[j + ((t - j) % period)] for t in range(n_iter, last))
            target = states[j + ((last - j) % period)]
            n_centers = target.shape[0]
            centers[:n_centers] = target
            if bar is not None:
                bar.update(last - n_iter)
            n_iter = last
            prev = None  # the state jumped: no previous pass to compare with
        elif not period:
            seen[key] = n_iter
            states.append(centers[:n_centers].copy())
        k_now, n_exp = classifier.classify(centers, n_centers, dist, label)
        if settle:
            energies.append(_energy(sizes, dist))
        n_expanded += n_exp
        n_iter += 1
        n_passes += 1
        n_orphans += k_now - n_centers
        orphans_per_pass.append(k_now - n_centers)
        used = centers[:k_now].copy()
        if tol > 0 and prev is not None:
            changed = float(sizes[label != prev].sum()) / total
            if changed <= tol:
                converged = by_tol = True
                break
        moved = update_centers(label, k_now, sizes, positions, used)
        if min_move > 0:
            hold_small_moves(moved, used, positions, min_move)
        hold_fixed(moved, used, fixed)
        if settle:
            recent.hold(used, moved, held)
            stay = held[used] & (moved >= 0)
            moved[stay] = used[stay]
        n_moved = int((moved != used).sum())
        if bar is not None:
            passes_done(bar, n_iter, max_iter, k_now, n_moved, changed if prev is not None
                        else -1.0, tol)
        if k_now == n_centers and n_moved == 0:
            converged = True
            break
        if n_iter >= max_iter:
            break
        alive, keep, slot, by_key = _next_list(moved, order)
        n_centers = alive.shape[0]
        centers[:n_centers] = alive
        if settle:
            recent.compact(keep, by_key)
        if tol > 0:  # superfacet s is number remap[s] in the next pass (-1: it died)
            remap = np.where(keep, slot, -1).astype(np.int32)
            # (into the previous pass's array: one array of labels, not two at a time)
            prev = gather(remap, label, out=prev)
    return Iteration(label=label, centers=used, n_iter=n_iter, converged=converged, dist=dist,
                     n_orphan_seeds=n_orphans, n_passes=n_passes, cycle_period=period,
                     expansions=n_expanded, changed=changed, stopped_by_tol=by_tol,
                     settled=int(held.sum()) if settle else 0)


def _next_list(moved: np.ndarray, order: np.ndarray | None) -> tuple:
    """The next pass's centers: the update's (``moved``, -1 for a superfacet that died)
    without the dead, listed by ``order`` of their elements where given. Also which
    superfacets live on, the place of each in the new list, and the permutation that
    listed them (None: in the order they were)."""
    keep = moved >= 0
    alive = moved[keep]
    slot = np.cumsum(keep) - 1
    if order is None:
        return alive, keep, slot, None
    by_key = np.argsort(order[alive], kind="stable")
    place = np.empty(alive.shape[0], dtype=np.int64)
    place[by_key] = np.arange(alive.shape[0])
    return alive[by_key], keep, place[np.maximum(slot, 0)], by_key


class _Recent:
    """The last :data:`RECENT` centers of each superfacet (by its place in the list): a
    center the update sends back to one of them is held where it is. Several centers
    oscillating out of phase keep the whole list from repeating (a cycle of the list is
    then never seen); each one's own return is."""

    def __init__(self) -> None:
        self.rows = np.full((0, RECENT), -1, dtype=np.int64)
        self.at = 0

    def hold(self, used: np.ndarray, moved: np.ndarray, held: np.ndarray) -> None:
        k = used.shape[0]
        if self.rows.shape[0] < k:  # (orphan centers: new superfacets, no past)
            self.rows = np.r_[self.rows, np.full((k - self.rows.shape[0], RECENT), -1)]
        back = (moved >= 0) & (moved != used) & (self.rows[:k] == moved[:, None]).any(axis=1)
        held[used[back]] = True
        self.rows[:k, self.at % RECENT] = used
        self.at += 1

    def compact(self, keep: np.ndarray, by_key: np.ndarray | None = None) -> None:
        self.rows = self.rows[:keep.shape[0]][keep]
        if by_key is not None:  # (the list put in order: each history follows its center)
            self.rows = self.rows[by_key]


#: Past centers of a superfacet a return to which holds it (:class:`_Recent`).
RECENT = 4


#: Elements whose products the energy sums at a time (:func:`_product_sum`): 512 KiB; at
#: least 128, the blocks numpy's pairwise summation adds without splitting them.
ENERGY_BLOCK = 1 << 16


def _energy(sizes: np.ndarray, dist: np.ndarray) -> float:
    """The classification's energy: the size-weighted sum of each element's distance to
    its center (elements no center reached left out)."""
    # (not np.dot: a BLAS call wakes OpenBLAS's threads, which then spin against the
    # compiled kernels' threads and slowed the whole run by half)
    energy = float(_product_sum(sizes, dist, np.empty(min(sizes.size, ENERGY_BLOCK))))
    if np.isfinite(energy):  # (every element reached: the usual case, one pass)
        return energy
    reached = np.isfinite(dist)
    return float((sizes[reached] * dist[reached]).sum())


def _product_sum(a: np.ndarray, b: np.ndarray, buf: np.ndarray):
    """``(a * b).sum()`` of two (n,) float arrays, the same bits, without a temporary of
    ``n``: the halves numpy's pairwise summation adds (``n // 2``, less its remainder by
    8) are split the same way down to blocks of ``buf``'s length, each summed by numpy
    (the products' pages no longer faulted in every pass)."""
    n = a.shape[0]
    if n <= buf.shape[0]:
        return np.multiply(a, b, out=buf[:n]).sum()
    half = n // 2
    half -= half % 8
    return _product_sum(a[:half], b[:half], buf) + _product_sum(a[half:], b[half:], buf)


def _settle(centers: np.ndarray, states: list, energies: list, first: int,
            held: np.ndarray) -> int:
    """Settle a cycle of center lists: the passes ``first ..`` of ``states`` (their
    classifications' ``energies``) repeat. Puts the list of the pass of lowest energy in
    ``centers`` and marks in ``held`` its centers that some pass of the cycle did not
    have (those that moved); returns the list's length."""
    cycle = range(first, len(states))
    best = states[min(cycle, key=lambda t: (energies[t], t))]
    always = best
    for t in cycle:
        always = always[np.isin(always, states[t])]
    held[best[~np.isin(best, always)]] = True
    centers[:best.shape[0]] = best
    return int(best.shape[0])


def hold_fixed(new: np.ndarray, old: np.ndarray, fixed: np.ndarray | None) -> None:
    """Keep in place (``new[s] = old[s]``) each center on a ``fixed`` element (an empty
    superfacet's -1 stays; None: none fixed)."""
    if fixed is None:
        return
    held = (old >= 0) & (new >= 0)
    held[held] = fixed[old[held]]
    new[held] = old[held]


def hold_small_moves(new: np.ndarray, old: np.ndarray, positions: np.ndarray,
                     min_move: float) -> int:
    """Keep in place (``new[s] = old[s]``) each center the update moved by
    less than ``min_move`` (mesh units, between element positions); return
    how many were kept."""
    s = np.flatnonzero((new != old) & (new >= 0) & (old >= 0))
    if s.shape[0] == 0:
        return 0
    step = positions[new[s]] - positions[old[s]]
    small = s[np.einsum("ij,ij->i", step, step) < min_move * min_move]
    new[small] = old[small]
    return int(small.shape[0])


def final_centers(labels: np.ndarray, old_centers: np.ndarray, sizes: np.ndarray,
                  positions: np.ndarray) -> np.ndarray:
    """Center of each final label: an old center that kept its label (the first
    one, in order), else the element nearest the size-weighted mean.

    Parameters
    ----------
    labels : (n,) int64 ndarray
        Dense labels ``0..K-1``.
    old_centers : (p,) int64 ndarray
        Centers of the last classification, of the labels before clean-up.
    sizes, positions : ndarray
        Element sizes and positions.

    Returns
    -------
    (K,) int64 ndarray
    """
    k = int(labels.max()) + 1
    out = update_centers(labels.astype(np.int32), k, sizes, positions,
                         np.full(k, -1, dtype=np.int64))
    kept = labels[old_centers]
    first = np.unique(kept, return_index=True)[1]
    out[kept[first]] = old_centers[first]
    return out
