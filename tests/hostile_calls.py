"""Hostile arguments for the compiled kernels, run in a process of its own.

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


def call(calls: dict, path: str, i: int, j, how: str):
    """The kernel ``path`` on copies of its recorded arguments, argument ``i`` spoilt."""
    from superfacets._kernels import native

    def copy(x):
        if isinstance(x, np.ndarray):
            return x.copy()
        return tuple(map(copy, x)) if isinstance(x, tuple) else x

    args, kwargs = calls[path]
    args = [copy(a) for a in args]
    if j is None:
        args[i] = spoilt(args[i], how)
    else:
        parts = list(args[i])
        parts[j] = spoilt(parts[j], how)
        args[i] = tuple(parts)
    return native.kernel(path)(*args, **copy(kwargs))


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
    main(sys.argv[1])
