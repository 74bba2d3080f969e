"""Kernels over contiguous ranges on several threads (private).

The kernels called this way release the GIL and write disjoint parts of
their outputs, so the results are the same for any number of threads.
"""

from __future__ import annotations

import resource
import threading
from contextlib import contextmanager
from contextvars import ContextVar

from .._kernels import native
from ..checks import check_threads
from .memory import address_space_left

#: Below this many items a range is not worth a second thread.
MIN_PER_THREAD = 100_000

_limit: ContextVar[int | None] = ContextVar("superfacets_threads", default=None)


def default_threads() -> int:
    """The thread count of the run in progress (:func:`using`), else the package's
    default (as ``n_threads=None``: ``SUPERFACETS_NUM_THREADS`` or the CPUs)."""
    n = _limit.get()
    if n is not None:
        return n

    return check_threads(None)


@contextmanager
def using(n_threads: int):
    """Within the block, :func:`split` makes at most ``n_threads`` ranges and the
    compiled kernels start at most ``n_threads`` threads (the pipeline's ``n_threads``
    also bounds the graph build it triggers). The compiled kernels' limit is the
    process's, as ``SUPERFACETS_NUM_THREADS`` is: runs on several Python threads at once
    share the last one set."""

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


def stack_room_threads() -> int | None:
    """The threads (the calling one included) whose stacks fit in half the address space
    this process has left under a limit (``ulimit -v``), or None: no limit. Beyond them a
    thread that starts can find no room for its thread-local data, which glibc does not
    refuse but aborts on (the compiled kernels' ``address_space_threads``: the same rule).

    Examples
    --------
    >>> n = stack_room_threads()
    >>> n is None or n >= 1
    True
    """
    room = address_space_left()
    if room is None:
        return None
    stack = threading.stack_size() or resource.getrlimit(resource.RLIMIT_STACK)[0]
    if stack == resource.RLIM_INFINITY or stack <= 0:
        stack = 8 * 2**20  # (glibc's default where the stack is unlimited)
    stack = max(stack, 65536)
    return 1 if room <= 2 * stack else 1 + min(4095, int(0.5 * room / stack))


def run_ranges(fn, bounds: list[int]) -> list:
    """``[fn(bounds[i], bounds[i + 1]) for i ...]``, the first range on the calling
    thread and the others on threads at the same time (:func:`in_parallel`)."""
    ranges = list(zip(bounds[:-1], bounds[1:]))
    return in_parallel(lambda i: fn(*ranges[i]), len(ranges))


def in_parallel(fn, n: int) -> list:
    """``[fn(0), ..., fn(n - 1)]``: ``fn(0)`` on the calling thread, the others on
    threads of their own at the same time (the kernels they call release the GIL, each
    writing its own part). A thread the system will not start (a limit on processes or
    memory: ``ulimit -u``, ``ulimit -v``) is not an error: its call runs on the calling
    thread after ``fn(0)``, the same result later. The first exception is raised once
    every call has ended: a Ctrl-C never leaves a thread running a kernel behind (one
    that returned into an interpreter being finalized aborted the process).
    :func:`wait_for_stragglers` waits for any the caller could not."""
    if n <= 1:
        return [fn(t) for t in range(n)]
    out: list = [None] * n
    errors: list = [None] * n
    ended = [threading.Event() for _ in range(n)]

    def call(t: int) -> None:
        try:
            out[t] = fn(t)
        except BaseException as exc:  # (raised below, once the others have ended)
            errors[t] = exc
        finally:
            ended[t].set()

    waits = []
    room = stack_room_threads()  # (None: no limit on the address space)
    try:  # (a Ctrl-C can land in a thread's start: the threads started are waited for)
        here = []
        for t in range(1, n):
            if room is not None and t >= room:  # (no room for its stack: as refused)
                here.append(t)
                continue
            th = threading.Thread(target=call, args=(t,), name="superfacets")
            try:
                waits.append(ended[t])
                _running.add(ended[t])
                th.start()
            except RuntimeError:  # "can't start new thread": no call of t to wait for
                waits.pop()
                _running.discard(ended[t])
                here.append(t)
        call(0)
        for t in here:
            call(t)
    except BaseException as exc:
        errors[0] = errors[0] or exc
    while True:
        try:
            _wait(waits)
            break
        except BaseException as exc:  # a Ctrl-C while waiting: wait again
            errors[0] = errors[0] or exc
    for exc in errors:
        if exc is not None:
            raise exc
    return out


#: the end of every call started on a thread of :func:`in_parallel` and not yet waited for
_running: set = set()


def _wait(events) -> None:
    for event in events:
        event.wait()
        _running.discard(event)


def wait_for_stragglers() -> None:
    """Wait until every call that :func:`in_parallel` started on a thread has ended (the
    command line, before the interpreter exits, with Ctrl-C ignored)."""
    _wait(list(_running))
