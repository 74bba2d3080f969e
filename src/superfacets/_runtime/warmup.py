"""Start numba in the background while the package and the mesh load.

A new Python process pays about 0.2-0.3 s the first time it calls any
numba kernel (numba's own start-up, before the cached machine code loads).
:func:`start` runs that first call (a trivial cached kernel) in a thread,
while the caller goes on reading the mesh; much of the start-up runs outside
the GIL (LLVM). Nothing starts at import: the command line calls it before
reading its input, and a script may do the same. Set
``SUPERFACETS_NO_WARMUP=1`` to turn it off. Where the compiled kernels are built
(:mod:`superfacets._kernels.native`), the default runs load no numba, and the
command line starts the warm-up only where they are missing.
"""

from __future__ import annotations

import atexit
import os
import sys
import threading
from pathlib import Path

__all__ = ["start", "wait", "cache_is_cold", "say_if_cold"]

_thread: threading.Thread | None = None


def _warm() -> None:
    try:
        import numpy as np

        from .._kernels.native import reference

        reset_labels = reference("expand.reset_labels")
        count_keys, scatter_keys, sort_buckets, triangle_half_edges, group_pairs, \
            csr_of_face_pairs = (reference(f"adjacency.{name}") for name in (
                "count_keys", "scatter_keys", "sort_buckets", "triangle_half_edges",
                "group_pairs", "csr_of_face_pairs"))

        reset_labels(np.empty(1), np.empty(1, dtype=np.int32))
        # the graph build's kernels, with the argument types of a triangle mesh's
        one = np.zeros(1, dtype=np.int32)
        faces = np.zeros((0, 3), dtype=np.int32)  # (as the readers give them)
        faces.setflags(write=False)  # a mesh's faces are read-only: the same specialization
        triangle_half_edges(faces, one, one, np.ones(1, dtype=bool))
        none = np.ones(1, dtype=bool)
        count_keys(one, none, 0, 1, np.zeros(1, dtype=np.int64))
        scatter_keys(one, none, 0, 1, np.zeros(1, dtype=np.int64), one.copy())
        sort_buckets(one, np.zeros(2, dtype=np.int64), one, 0, 1)
        group_pairs(np.zeros(1, dtype=np.int32), np.empty(0, dtype=np.int32), one, one)
        csr_of_face_pairs(one, one + 1, one, one, 2, np.empty(2, dtype=np.int32),
                          np.empty(2, dtype=np.int32))
    except Exception:  # never let the warm-up break an import; the real call will report
        pass


def start() -> None:
    """Start numba's start-up in a background thread, once per process.

    A no-op when already started or when ``SUPERFACETS_NO_WARMUP`` is set. Call it
    only where the run will use numba (not on faces where the kernels are compiled).

    Examples
    --------
    >>> from superfacets._runtime import warmup
    >>> warmup.start()   # then read the mesh; the first kernel call waits less
    """
    global _thread
    if _thread is not None or os.environ.get("SUPERFACETS_NO_WARMUP"):
        return
    _thread = threading.Thread(target=_warm, name="superfacets-warmup", daemon=True)
    _thread.start()
    atexit.register(_thread.join, 10.0)  # never exit while it is inside LLVM


def wait(timeout: float | None = None) -> None:
    """Wait until a started warm-up has finished (no-op when none was started)."""
    if _thread is not None:
        _thread.join(timeout)


def cache_is_cold() -> bool:
    """Whether numba has no machine code of this package's kernels cached yet.

    numba keeps it (``cache=True``) in ``__pycache__`` beside the kernels'
    sources, or, where that is not writable, under ``NUMBA_CACHE_DIR`` or the
    user's cache folder; the index files of the expansion kernels stand for all.
    """
    kernels = Path(__file__).resolve().parents[1] / "_kernels"
    if any((kernels / "__pycache__").glob("expand.*.nbi")):
        return False
    for root in (os.environ.get("NUMBA_CACHE_DIR"), Path.home() / ".cache" / "numba"):
        if root and Path(root).is_dir() and any(Path(root).rglob("expand.*.nbi")):
            return False
    return True


def say_if_cold(stream=None) -> bool:
    """On a terminal, say once (the first run after installing) that numba compiles the
    kernels now, so that a silent first run is not taken for a hang; return whether it
    said so."""
    stream = sys.stderr if stream is None else stream
    if not (getattr(stream, "isatty", lambda: False)() and cache_is_cold()):
        return False
    print("note: first run after installing: compiling the numba kernels once (about 10-40 s "
          "on 2 cores); later runs reuse them", file=stream, flush=True)
    return True
