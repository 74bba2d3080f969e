"""Kernels over contiguous ranges on several threads (private).

The kernels called this way release the GIL and write disjoint parts of
their outputs, so the results are the same for any number of threads.
"""

from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor
from contextlib import contextmanager
from contextvars import ContextVar

#: Below this many items a range is not worth a second thread.
MIN_PER_THREAD = 100_000

_limit: ContextVar[int | None] = ContextVar("superfacets_threads", default=None)


def default_threads() -> int:
    """The thread count of the run in progress (:func:`using`), else the package's
    default (as ``n_threads=None``: ``SUPERFACETS_NUM_THREADS`` or the CPUs)."""
    n = _limit.get()
    if n is not None:
        return n
    from ..method.params import check_threads

    return check_threads(None)


@contextmanager
def using(n_threads: int):
    """Within the block, :func:`split` makes at most ``n_threads`` ranges and the
    compiled kernels start at most ``n_threads`` threads (the pipeline's ``n_threads``
    also bounds the graph build it triggers). The compiled kernels' limit is the
    process's, as ``SUPERFACETS_NUM_THREADS`` is: runs on several Python threads at once
    share the last one set."""
    from .._kernels import native

    n = max(1, int(n_threads))
    token = _limit.set(n)
    previous = native.limit_threads(n)
    try:
        yield
    finally:
        native.limit_threads(previous)
        _limit.reset(token)


def split(n: int, n_threads: int | None = None, min_per_thread: int | None = None
          ) -> list[int]:
    """Bounds ``0 = b_0 < ... < b_t = n`` of about equal ranges, one per thread,
    each of at least ``min_per_thread`` items (default :data:`MIN_PER_THREAD`;
    one range when ``n`` is small)."""
    if n_threads is None:
        n_threads = default_threads()
    if min_per_thread is None:
        min_per_thread = MIN_PER_THREAD
    t = max(1, min(int(n_threads), n // max(1, min_per_thread)))
    return [n * i // t for i in range(t + 1)]


def run_ranges(fn, bounds: list[int]) -> list:
    """``[fn(bounds[i], bounds[i + 1]) for i ...]``, the first range on the calling
    thread and the others on a pool at the same time."""
    ranges = list(zip(bounds[:-1], bounds[1:]))
    if len(ranges) <= 1:
        return [fn(a, b) for a, b in ranges]
    with ThreadPoolExecutor(len(ranges) - 1, thread_name_prefix="superfacets") as pool:
        futures = [pool.submit(fn, a, b) for a, b in ranges[1:]]
        first = fn(*ranges[0])
        return [first] + [f.result() for f in futures]
