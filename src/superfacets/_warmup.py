"""Start numba in the background while the package and the mesh load.

A new Python process pays about 0.2-0.3 s the first time it calls any
numba kernel (numba's own start-up, before the cached machine code loads).
Importing :mod:`superfacets` starts a thread that makes that first call
(a trivial cached kernel) while the main thread goes on importing scipy
and reading the mesh; much of the start-up runs outside the GIL (LLVM).
Set ``SUPERFACETS_NO_WARMUP=1`` to turn it off.
"""

from __future__ import annotations

import atexit
import os
import threading

_thread: threading.Thread | None = None


def _warm() -> None:
    try:
        import numpy as np

        from . import _kernels

        _kernels.reset_labels(np.empty(1), np.empty(1, dtype=np.int32))
    except Exception:  # never let the warm-up break an import; the real call will report
        pass


def start() -> None:
    """Start the warm-up thread once per process (no-op when disabled)."""
    global _thread
    if _thread is not None or os.environ.get("SUPERFACETS_NO_WARMUP"):
        return
    _thread = threading.Thread(target=_warm, name="superfacets-warmup", daemon=True)
    _thread.start()
    atexit.register(_thread.join, 10.0)  # never exit while it is inside LLVM
