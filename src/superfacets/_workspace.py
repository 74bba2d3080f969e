"""Work buffers of the expansions, and the replayed classification.

Private. ``Workspaces`` holds, per thread, the per-expansion tentative
distances (``local``, float64), their expansion stamps (``stamp``, int32), the
bucket queue and a visit buffer, both grown on demand (the queue holds an
expansion's frontier, a few hundred to a few thousand faces, not ``m``). ``Replay`` is the
classification of :mod:`superfacets.segment` that re-expands only the centers
that moved and replays the recorded expansions of the others, running the new
expansions on several threads.
"""

from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor

import numpy as np

from . import _kernels

_SID_LIMIT = 2**31 - 2  # stamps are int32
_QUEUE0 = 1 << 14  # initial queue nodes
_VISIT0 = 1 << 16  # initial visit buffer
_ARENA = 5.0  # initial record arena, entries per face
_PARALLEL_MIN_WORK = 200_000  # recorded faces per pass worth a second thread
_MAX_BUCKETS = 1 << 16


def bucket_width(weights: np.ndarray) -> tuple[float, int]:
    """Bucket width of the expansion queue: ``(1 / width, number of buckets)``.

    A quarter of the median edge weight (measured: 1.0 faces processed per
    face reached, against 6.4 for a plain FIFO); wider if more than
    ``2**16`` buckets would be needed to span the largest weight. Any width
    gives the same distances (see :func:`superfacets._kernels.expand`).
    """
    if weights.shape[0] == 0:
        return 1.0, 2
    wmax = float(weights.max())
    pos = weights[weights > 0]
    width = 0.25 * float(np.median(pos)) if pos.shape[0] else 1.0
    width = max(width, wmax / (_MAX_BUCKETS - 2))
    if not (np.isfinite(width) and width > 0):
        width = 1.0
    nb = 2
    while nb < wmax / width + 2:
        nb *= 2
    return 1.0 / width, nb


class Workspace:
    """``local``, ``stamp``, bucket queue and visit buffer of one thread.

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
        self.local = np.empty(m)
        self.stamp = np.full(m, -1, dtype=np.int32)
        self.max_nodes = max_nodes
        self.head = np.full(n_buckets, -1, dtype=np.int64)
        self._queue(min(_QUEUE0, max_nodes))
        self.vis = np.empty(min(_VISIT0, m), dtype=np.int32)
        self._labels = None

    def labels(self):
        """This thread's own ``(dist, label)`` (float64, int32), made on first use."""
        if self._labels is None:
            self._labels = (np.empty(self.m), np.empty(self.m, dtype=np.int32))
        return self._labels

    def _queue(self, cap: int) -> None:
        self.qface = np.empty(cap, dtype=np.int32)
        self.qdist = np.empty(cap)
        self.qnext = np.empty(cap, dtype=np.int32)
        self.queue = (self.qface, self.qdist, self.qnext, self.head)

    def grow(self, status: int) -> None:
        """Quadruple the buffer a kernel ran out of (``status``) and reset the
        stamps, so the interrupted expansion can be run again with its id.

        ``RECORD_FULL`` grows the visit buffer (callers whose records go to an
        arena of their own handle that status themselves).
        """
        self.stamp.fill(-1)
        if status == _kernels.QUEUE_FULL:
            cap = self.qface.shape[0]
            if cap >= self.max_nodes:  # cannot happen: the bound holds every push
                raise RuntimeError("expansion queue overflow beyond its bound")
            self._queue(min(self.max_nodes, 4 * cap))
        elif status == _kernels.RECORD_FULL:
            self.vis = np.empty(min(self.m, 4 * self.vis.shape[0]), dtype=np.int32)
        else:
            raise ValueError(f"unknown status {status}")


class Workspaces:
    """One :class:`Workspace` per thread and the expansion-id counter.

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
        self.sid = 0
        self._pool = None

    def get(self, t: int) -> Workspace:
        while len(self.ws) <= t:
            self.ws.append(Workspace(self.m, self.n_buckets, self.heap_bound))
        return self.ws[t]

    def reserve(self, n: int) -> int:
        """Return the first of ``n`` fresh expansion ids (stamps reset on wrap)."""
        if self.sid + n >= _SID_LIMIT:
            for w in self.ws:
                w.stamp.fill(-1)
            self.sid = 0
        sid = self.sid
        self.sid += n
        return sid

    def release(self, next_sid: int) -> None:
        """Give back the reserved ids from ``next_sid`` on (unused by the kernel)."""
        self.sid = int(next_sid)

    def pool(self) -> ThreadPoolExecutor:
        if self._pool is None:
            self._pool = ThreadPoolExecutor(self.n_threads - 1, thread_name_prefix="superfacets")
        return self._pool

    def close(self) -> None:
        if self._pool is not None:
            self._pool.shutdown()
            self._pool = None


def with_room(ws: Workspace, call):
    """Run ``call(ws)`` (a kernel returning a status first or alone) until the
    queue and visit buffer of ``ws`` were large enough."""
    while True:
        out = call(ws)
        st = out[0] if isinstance(out, tuple) else out
        if st not in (_kernels.QUEUE_FULL, _kernels.RECORD_FULL):
            return out
        ws.grow(st)


class Replay:
    """The bounded classification with recorded expansions (see ``segment``).

    The expansions of the previous pass are kept in one arena (``face``
    int32 and ``dist`` float64, one entry per settled face, ``start``/``len``
    per center). A center whose face was a center in the previous pass
    reuses its record; the others are expanded (record only, on up to
    ``n_threads`` threads), all records are merged (each new one right after
    its expansion, on its thread; :func:`~superfacets._kernels.merge_some`)
    and orphans are seeded. The
    arena is compacted (records of centers that moved are dropped) when the
    free space at its end runs short, and grown when that is not enough.
    """

    def __init__(self, m: int, spaces: Workspaces):
        self.m = m
        self.spaces = spaces
        cap = int(_ARENA * m) + 1024
        self.face = np.empty(cap, dtype=np.int32)
        self.dist = np.empty(cap)
        self.end = 0
        self.slot = np.full(m, -1, dtype=np.int32)  # face -> index among previous centers
        self.prev_centers = np.empty(0, dtype=np.int64)
        self.prev_start = np.empty(0, dtype=np.int64)
        self.prev_len = np.empty(0, dtype=np.int64)

    # -- arena -------------------------------------------------------------
    def _make_room(self, need: int, start: np.ndarray, length: np.ndarray) -> None:
        """Free ``need`` entries at the end, keeping the segments ``start``/``length``
        (``start`` updated in place)."""
        if self.face.shape[0] - self.end >= need:
            return
        self.end = int(_kernels.compact_records(np.argsort(start, kind="stable"), start,
                                                 length, self.face, self.dist))
        if self.face.shape[0] - self.end >= need:
            return
        self._grow(int(0.25 * (self.end + need)) + need + 1024 - (self.face.shape[0] - self.end))

    def _grow(self, extra: int) -> None:
        """Enlarge the arena by ``extra`` entries, keeping ``[0, end)``."""
        cap = self.face.shape[0] + max(int(extra), 1024)
        face = np.empty(cap, dtype=np.int32)
        dist = np.empty(cap)
        face[:self.end] = self.face[:self.end]
        dist[:self.end] = self.dist[:self.end]
        self.face, self.dist = face, dist

    def classify(self, indptr, indices, w, c, centers, n_centers, window_r2, dist, label):
        """Classify; return ``(K, n_expanded)`` like ``classify_bounded``."""
        spaces = self.spaces
        cs = centers[:n_centers]
        idx = self.slot[cs]
        reuse = idx >= 0
        seg_start = np.empty(self.m + 1, dtype=np.int64)  # per center (orphans appended)
        seg_len = np.empty(self.m + 1, dtype=np.int64)
        kept = np.flatnonzero(reuse)
        todo = np.flatnonzero(~reuse)
        seg_start[kept] = self.prev_start[idx[kept]]
        seg_len[kept] = self.prev_len[idx[kept]]
        if self.prev_len.shape[0]:
            expected = int(1.1 * todo.shape[0] * self.prev_len.mean())
        else:  # first pass: each face lies in about 4.4 windows
            expected = int(0.9 * self.face.shape[0])
        # room for the new expansions, keeping only the records reused now
        while True:
            ks = seg_start[kept]
            self._make_room(expected + 4096, ks, seg_len[kept])
            seg_start[kept] = ks
            st = self._expand_and_merge(indptr, indices, w, c, cs, window_r2, seg_start,
                                        seg_len, kept, todo, expected, dist, label)
            if st >= 0:
                break
            # a thread ran out of room: make more (at least twice what was expected), redo
            expected = 2 * max(expected, self.face.shape[0] - self.end)
        new_end = st
        # orphans (sequential: they depend on the labels)
        ws = spaces.get(0)
        while True:
            sid = spaces.reserve(self.m - n_centers + 1)
            p, k, next_sid = _kernels.seed_orphans(
                indptr, indices, w, c, centers, n_centers, window_r2, dist, label, ws.local,
                ws.stamp, sid, ws.queue, spaces.inv_width, self.face, self.dist, new_end,
                self.face.shape[0], seg_start, seg_len)
            spaces.release(next_sid)
            if p >= 0:
                break
            # undo the orphans' labels: merge everything again, then retry with more room
            if p == _kernels.QUEUE_FULL:
                ws.grow(p)
            else:
                self.end = new_end
                self._grow(self.face.shape[0] // 2)
            self._merge_only(n_centers, seg_start, seg_len, dist, label)
        self.end = int(p)
        # this pass's records become the previous ones
        self.slot[self.prev_centers] = -1
        self.prev_centers = centers[:k].copy()
        self.slot[self.prev_centers] = np.arange(k, dtype=np.int32)
        self.prev_start = seg_start[:k].copy()
        self.prev_len = seg_len[:k].copy()
        return k, int(todo.shape[0]) + (k - n_centers)

    def _merge_only(self, n_centers, seg_start, seg_len, dist, label) -> None:
        _kernels.reset_labels(dist, label)
        _kernels.merge_some(np.arange(n_centers), seg_start, seg_len, self.face, self.dist,
                            dist, label)

    def _expand_and_merge(self, indptr, indices, w, c, cs, window_r2, seg_start, seg_len,
                          kept, todo, expected, dist, label):
        """Expand the centers ``todo`` into the free end of the arena and merge
        every record (those of ``kept`` and the new ones) into ``dist``/``label``.

        Thread ``t`` expands an interleaved share of ``todo`` into its own part
        of the arena and merges its new records, while they are in cache, and a
        share of the reused ones into its own ``dist``/``label`` (thread 0: the
        caller's); the shares are then combined face by face. Returns the new
        end of the arena, or -1 if a thread ran out of room (nothing is kept).
        """
        spaces = self.spaces
        n = todo.shape[0]
        lo, hi = self.end, self.face.shape[0]
        n_thr = spaces.n_threads
        if n_thr <= 1 or expected + int(seg_len[kept].sum()) < _PARALLEL_MIN_WORK:
            n_thr = 1
        parts = [todo[t::n_thr] for t in range(n_thr)]  # interleaved: balanced work
        # reused records: each to the thread with the least work so far
        load = [len(p) * expected / max(n, 1) for p in parts]
        share = [[] for _ in range(n_thr)]
        for s, ln in zip(kept.tolist(), seg_len[kept].tolist()):
            t = min(range(n_thr), key=load.__getitem__)
            share[t].append(s)
            load[t] += ln
        bounds = [lo + (hi - lo) * t // n_thr for t in range(n_thr + 1)]
        per = (n + n_thr - 1) // n_thr
        sid0 = spaces.reserve(n_thr * per)  # thread t uses sid0 + t * per + i

        def run(t):
            ws = spaces.get(t)
            d_t, l_t = (dist, label) if t == 0 else ws.labels()
            part = parts[t]
            srcs_t = np.ascontiguousarray(cs[part])
            os_t = np.empty(part.shape[0], dtype=np.int64)
            ol_t = np.empty(part.shape[0], dtype=np.int64)
            while True:
                _kernels.reset_labels(d_t, l_t)
                _kernels.merge_some(np.array(share[t], dtype=np.int64), seg_start, seg_len,
                                    self.face, self.dist, d_t, l_t)
                p = _kernels.expand_many(indptr, indices, w, c, srcs_t, part, window_r2,
                                         ws.local, ws.stamp, sid0 + t * per, ws.queue,
                                         spaces.inv_width, self.face, self.dist, bounds[t],
                                         bounds[t + 1], os_t, ol_t, d_t, l_t)
                if p != _kernels.QUEUE_FULL:
                    break
                ws.grow(p)
            seg_start[part] = os_t
            seg_len[part] = ol_t
            return p

        if n_thr == 1:
            ends = [run(0)]
        else:
            futs = [spaces.pool().submit(run, t) for t in range(1, n_thr)]
            ends = [run(0)] + [f.result() for f in futs]
        if min(ends) < 0:
            return -1
        if n_thr > 1:
            cuts = [self.m * t // n_thr for t in range(n_thr + 1)]

            def combine(t):
                for u in range(1, n_thr):
                    _kernels.combine_merged(dist, label, *spaces.get(u).labels(), cuts[t],
                                            cuts[t + 1])

            futs = [spaces.pool().submit(combine, t) for t in range(1, n_thr)]
            combine(0)
            for f in futs:
                f.result()
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
