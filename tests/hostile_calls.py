"""Hostile arguments for the compiled kernels, run in a process of its own.

``python hostile_calls.py CALLS.pkl scalars [SECONDS]``: each scalar argument (a count, a
size, a cap, a double bounding a loop) spoilt in turn, and each array inside a tuple
argument emptied, each case in a forked child killed past SECONDS (a hang).


``python hostile_calls.py CALLS.pkl``: for each recorded kernel call (``{path: (args,
kwargs)}``, the first call of each kernel in real runs), each integer array among its
arguments is spoiled in turn (an entry set to a huge value, to a negative one, and its
largest entry raised past any length) and the call made again on copies. Each case prints
``CASE`` before the call and ``RESULT <outcome>`` after it: a kernel that reads or writes
outside its arrays ends this process (SIGSEGV, SIGBUS) or hangs, and the caller sees which
case did. Outcomes: ``ok``, or the exception's type name.
"""

from __future__ import annotations

import pickle
import resource
import sys

import numpy as np


def spoilt(arr: np.ndarray, how: str) -> np.ndarray:
    """A copy of the integer array ``arr`` with one entry spoilt."""
    out = arr.copy()
    flat = out.reshape(-1)
    info = np.iinfo(out.dtype)
    if how == "huge":
        flat[flat.size // 2] = info.max // 2 if out.dtype.itemsize >= 4 else info.max
    elif how == "negative":
        flat[flat.size // 2] = -7
    else:  # "past": the largest entry past any length
        flat[int(np.argmax(flat))] = min(int(flat.max()) + 1_000_003, info.max)
    return out


def cases(calls: dict):
    """(path, argument, member, how) of every spoilt call: member indexes a tuple argument."""
    for path in sorted(calls):
        args, _ = calls[path]
        for i, a in enumerate(args):
            parts = ([(None, a)] if isinstance(a, np.ndarray) else
                     list(enumerate(a)) if isinstance(a, tuple) else [])
            for j, x in parts:
                if not isinstance(x, np.ndarray) or x.dtype.kind not in "iu" or x.size == 0:
                    continue
                for how in ("huge", "negative", "past"):
                    if how == "negative" and x.dtype.kind == "u":
                        continue
                    yield path, i, j, how


def copy(x):
    """A copy of an argument: arrays copied, tuples of them too; anything else as it is."""
    if isinstance(x, np.ndarray):
        return x.copy()
    return tuple(map(copy, x)) if isinstance(x, tuple) else x


def call(calls: dict, path: str, i: int, j, how: str):
    """The kernel ``path`` on copies of its recorded arguments, argument ``i`` spoilt."""
    from superfacets._kernels import native

    args, kwargs = calls[path]
    args = [copy(a) for a in args]
    if j is None:
        args[i] = spoilt(args[i], how)
    else:
        parts = list(args[i])
        parts[j] = spoilt(parts[j], how)
        args[i] = tuple(parts)
    return native.kernel(path)(*args, **copy(kwargs))


#: The values a scalar argument is spoilt with: counts and sizes of 0, -1 and past any
#: memory; doubles that bound loops, not finite or not positive.
INTS = (0, -1, 2**62, 2**31)
FLOATS = (float("nan"), float("inf"), -float("inf"), 0.0, -1.0)


def scalar_cases(calls: dict):
    """(path, argument, member, value) of every call with one scalar spoilt, or one array
    emptied (member ``'all'``: the argument; an int: its place in a tuple argument;
    value: None)."""
    for path in sorted(calls):
        args, _ = calls[path]
        for i, a in enumerate(args):
            if isinstance(a, (bool, np.bool_)):
                continue
            if isinstance(a, (int, np.integer)):
                yield from ((path, i, None, v) for v in INTS)
            elif isinstance(a, (float, np.floating)):
                yield from ((path, i, None, v) for v in FLOATS)
            elif isinstance(a, np.ndarray) and a.size:
                yield path, i, "all", None  # (the array emptied: a cap, a buffer of 0)
            elif isinstance(a, tuple):
                yield from ((path, i, j, None) for j, x in enumerate(a)
                            if isinstance(x, np.ndarray))


def scalar_call(calls: dict, path: str, i: int, j, value):
    """The kernel ``path`` on copies of its recorded arguments, argument ``i`` (or member
    ``j`` of it, emptied) spoilt."""
    from superfacets._kernels import native

    args, kwargs = calls[path]
    args = [copy(a) for a in args]
    if j is None:
        args[i] = value
    elif j == "all":
        args[i] = args[i][:0]
    else:
        parts = list(args[i])
        parts[j] = parts[j][:0]
        args[i] = tuple(parts)
    return native.kernel(path)(*args, **copy(kwargs))


def forked(run, limit: float, memory: int = 4 << 30) -> str:
    """``run()`` in a forked child (its address space bounded by ``memory`` bytes), killed
    past ``limit`` seconds: ``ok``, the type name of what it raised, ``crash <signal>`` or
    ``hang``."""
    import os
    import signal
    import time

    r, w = os.pipe()
    pid = os.fork()
    if pid == 0:  # the child: its outcome through the pipe
        os.close(r)
        resource.setrlimit(resource.RLIMIT_AS, (memory, memory))
        try:
            run()
            outcome = "ok"
        except BaseException as exc:  # noqa: BLE001 (each outcome reported)
            outcome = type(exc).__name__
        os.write(w, outcome.encode())
        os._exit(0)
    os.close(w)
    t0, status = time.monotonic(), None
    while time.monotonic() - t0 < limit:
        done, got = os.waitpid(pid, os.WNOHANG)
        if done:
            status = got
            break
        time.sleep(0.002)
    if status is None:
        os.kill(pid, signal.SIGKILL)
        os.waitpid(pid, 0)
    said = os.read(r, 200).decode(errors="replace")
    os.close(r)
    if status is None:
        return "hang"
    return f"crash {os.WTERMSIG(status)}" if os.WIFSIGNALED(status) else said or "silent"


def scalars(path: str, limit: float) -> None:
    """Each scalar case in a forked child of its own, killed past ``limit`` seconds: prints
    ``CASE``, then ``RESULT <outcome>`` (:func:`forked`)."""
    with open(path, "rb") as f:
        calls = pickle.load(f)
    for case in scalar_cases(calls):
        print("CASE", *case, flush=True)
        print("RESULT", forked(lambda: scalar_call(calls, *case), limit), flush=True)
    print("DONE", flush=True)


def main(path: str) -> None:
    resource.setrlimit(resource.RLIMIT_AS, (8 << 30, 8 << 30))  # (a huge allocation fails)
    with open(path, "rb") as f:
        calls = pickle.load(f)
    for case in cases(calls):
        print("CASE", *case, flush=True)
        try:
            call(calls, *case)
            outcome = "ok"
        except Exception as exc:  # noqa: BLE001 (each outcome reported)
            outcome = type(exc).__name__
        print("RESULT", outcome, flush=True)
    print("DONE", flush=True)


if __name__ == "__main__":
    if len(sys.argv) > 2 and sys.argv[2] == "scalars":
        scalars(sys.argv[1], float(sys.argv[3]) if len(sys.argv) > 3 else 20.0)
    else:
        main(sys.argv[1])
