"""Kernels over contiguous ranges on several threads (private).

The kernels called this way release the GIL and write disjoint parts of
their outputs, so the results are the same for any number of threads.
"""

from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor

#: Below this many items a range is not worth a second thread.
MIN_PER_THREAD = 100_000


def default_threads() -> int:
    """The package's default thread count (numba's, as ``n_threads=None``)."""
    from .params import check_threads

    return check_threads(None)


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
