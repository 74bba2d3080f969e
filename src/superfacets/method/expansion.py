"""Work buffers of the bounded expansions (used by the classification and the flood).

:class:`Workspaces` holds, per thread, the per-expansion tentative distances
(``local``, float64, ``+0.0`` between expansions: each expansion puts back
the values it changed), the bucket queue and a visit buffer, both grown on
demand (the queue holds one expansion's frontier, a few hundred to a few
thousand elements, not ``n``). :func:`with_room` reruns a kernel until its
buffers were large enough; :func:`centers_within` finds the centers near others.
"""

from __future__ import annotations

import numpy as np

from .._kernels.codes import QUEUE_FULL, RECORD_FULL

__all__ = ["Workspace", "Workspaces", "bucket_width", "centers_within", "with_room"]

_QUEUE0 = 1 << 14  # initial queue nodes
_VISIT0 = 1 << 16  # initial visit buffer
_MAX_BUCKETS = 1 << 16


def bucket_width(weights: np.ndarray) -> tuple[float, int]:
    """Bucket width of the expansion queue: ``(1 / width, number of buckets)``.

    A quarter of the median edge weight (measured: 1.0 faces processed per
    face reached, against 6.4 for a plain FIFO; the median of a strided
    sample of ``2**17`` weights on large graphs); wider if more than
    ``2**16`` buckets would be needed to span the largest weight. Any width
    gives the same distances (see the expansion kernel's notes).
    """
    if weights.shape[0] == 0:
        return 1.0, 2
    wmax = float(weights.max())
    # the median of an evenly strided sample of at most ~2**17 weights: any width gives
    # the same distances, so an estimate does (a full median costs 0.35 s at 13M entries)
    sample = weights[::max(1, weights.shape[0] >> 17)]
    pos = sample[sample > 0]
    width = 0.25 * float(np.median(pos)) if pos.shape[0] else 1.0
    width = max(width, wmax / (_MAX_BUCKETS - 2))
    if not (np.isfinite(width) and width > 0):
        width = 1.0
    nb = 2
    while nb < wmax / width + 2:
        nb *= 2
    return 1.0 / width, nb


#: The dense scratch a run gives the compiled expansions: none (see :class:`Workspace`)
_NO_SCRATCH = np.zeros(0)


class Workspace:
    """Bucket queue and visit buffer of one thread (and ``local``, empty: the reference
    kernels' dense scratch distances, which the compiled ones keep in a table of their
    own).

    Parameters
    ----------
    m : int
        Number of faces.
    n_buckets : int
        Buckets of the queue (a power of two, from :func:`bucket_width`).
    max_nodes : int
        Bound on the queue nodes (``len(indices) + m + 1``).
    """

    def __init__(self, m: int, n_buckets: int, max_nodes: int):
        self.m = m
        # the argument where the reference kernels keep their dense scratch distances
        # (one per element): the compiled expansions keep theirs in a table of their own,
        # the size of their largest expansion, so a run gives them none
        self.local = _NO_SCRATCH
        self.max_nodes = max_nodes
        self.head = np.full(n_buckets, -1, dtype=np.int64)
        self._queue(min(_QUEUE0, max_nodes))
        self.vis = np.empty(min(_VISIT0, m), dtype=np.int32)

    def _queue(self, cap: int) -> None:
        self.qface = np.empty(cap, dtype=np.int32)
        self.qdist = np.empty(cap)
        self.qnext = np.empty(cap, dtype=np.int32)
        self.queue = (self.qface, self.qdist, self.qnext, self.head)

    def grow(self, status: int) -> None:
        """Quadruple the buffer a kernel ran out of (``status``), so the
        interrupted expansion can be run again (it left ``local`` all ``inf``).

        ``RECORD_FULL`` grows the visit buffer (callers whose records go to an
        arena of their own handle that status themselves).
        """
        if status == QUEUE_FULL:
            cap = self.qface.shape[0]
            if cap >= self.max_nodes:  # cannot happen: the bound holds every push
                raise RuntimeError("expansion queue overflow beyond its bound")
            self._queue(min(self.max_nodes, 4 * cap))
        elif status == RECORD_FULL:
            self.vis = np.empty(min(self.m, 4 * self.vis.shape[0]), dtype=np.int32)
        else:
            raise ValueError(f"unknown status {status}")


class Workspaces:
    """One :class:`Workspace` per thread and the threads' pool.

    Parameters
    ----------
    m : int
        Number of faces.
    weights : (2 e,) float64 ndarray
        Edge weight of each CSR entry (sets the bucket width, bounds the queue).
    n_threads : int
        Threads that may expand at once (``>= 1``); workspaces beyond the
        first are allocated on first use.
    """

    def __init__(self, m: int, weights: np.ndarray, n_threads: int = 1):
        self.m = m
        self.heap_bound = weights.shape[0] + m + 1
        self.inv_width, self.n_buckets = bucket_width(weights)
        self.n_threads = max(1, int(n_threads))
        self.ws = [Workspace(m, self.n_buckets, self.heap_bound)]

    def get(self, t: int) -> Workspace:
        while len(self.ws) <= t:
            self.ws.append(Workspace(self.m, self.n_buckets, self.heap_bound))
        return self.ws[t]

    def release(self) -> None:
        """Forget every thread's workspace (its queue and visit buffer), as between uses
        that hold other large arrays (the swaps of split-and-merge); :meth:`get` makes
        them again."""
        self.ws.clear()

    def close(self) -> None:
        """Forget the workspaces."""
        self.release()


def with_room(ws: Workspace, call):
    """Run ``call(ws)`` (a kernel returning a status first or alone) until the
    queue and visit buffer of ``ws`` were large enough."""
    while True:
        out = call(ws)
        st = out[0] if isinstance(out, tuple) else out
        if st not in (QUEUE_FULL, RECORD_FULL):
            return out
        ws.grow(st)


def centers_within(p: np.ndarray, reach: np.ndarray, q: np.ndarray) -> np.ndarray | None:
    """Which points ``q`` lie within ``reach[i]`` of some point ``p[i]``.

    Used to find the centers whose windows can meet a moved center's (the
    classification's in-place passes). Read from a grid of pitch ``reach.max()``:
    each ``p[i]`` looks in the 27 cells around its own.

    Parameters
    ----------
    p : (a, 3) float64 ndarray
    reach : (a,) float64 ndarray
        Radius around each ``p[i]`` (input units, ``> 0``), widened by a millionth
        so that rounding never leaves a point out.
    q : (b, 3) float64 ndarray

    Returns
    -------
    (b,) bool ndarray or None
        None where the grid would have more than ``2**60`` cells, or ``reach`` is
        not positive and finite.

    Examples
    --------
    >>> centers_within(np.zeros((1, 3)), np.array([1.0]),
    ...                np.array([[0.5, 0, 0], [0, 2.0, 0], [0, 0, -1.0]])).tolist()
    [True, False, True]
    """
    h = float(reach.max()) * (1.0 + 1e-6)
    if not (np.isfinite(h) and h > 0):
        return None
    lo = np.minimum(p.min(axis=0), q.min(axis=0)) - h  # a cell of margin: no key wraps
    dims = np.floor((np.maximum(p.max(axis=0), q.max(axis=0)) + h - lo) / h).astype(np.int64) + 2
    if float(np.prod(dims.astype(np.float64))) > 2.0**60:
        return None
    mult = np.array([dims[1] * dims[2], dims[2], 1], dtype=np.int64)
    kq = np.floor((q - lo) / h).astype(np.int64) @ mult
    kp = np.floor((p - lo) / h).astype(np.int64) @ mult
    order = np.argsort(kq, kind="stable")
    sk = kq[order]
    near = np.zeros(q.shape[0], dtype=bool)
    for off in np.array(np.meshgrid([-1, 0, 1], [-1, 0, 1], [-1, 0, 1])).reshape(3, -1).T:
        key = kp + off @ mult
        a, b = np.searchsorted(sk, key, "left"), np.searchsorted(sk, key, "right")
        n = b - a
        rows = order[np.repeat(a - np.cumsum(n) + n, n) + np.arange(int(n.sum()))]
        i = np.repeat(np.arange(p.shape[0]), n)
        d2 = ((q[rows] - p[i]) ** 2).sum(axis=1)
        near[rows[d2 <= (reach[i] * (1.0 + 1e-6)) ** 2]] = True
    return near
