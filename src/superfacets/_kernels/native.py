"""The compiled kernels where they are built, the numba kernels otherwise (private).

``superfacets._kernels._cxx`` (C++, built by ``pip install``) holds the kernels of the
default run on faces: the graph build, the bounded expansions, the center update,
the farthest-point sampling, split-and-merge, the clean-up and the connectivity step.
Each is the numba kernel of the same name, the same operations in the same order, so
the labels are the same bit for bit (``tests/test_native.py``). With them a run on
faces loads no numba at all: no compilation on the first run after installing, and
no numba start-up (about 0.45 s) on every later one.

:func:`kernel` gives the callable for ``"module.name"``: the compiled kernel, which
takes exactly the dtypes and layouts of the run on faces and raises its ``Mismatch``
(a ``TypeError``) on anything else, before touching any array; the numba kernel
(imported then) runs that call instead. ``SUPERFACETS_NATIVE=0`` in the environment
turns the compiled kernels off (numba for everything, as where no compiler was found
at install time).
"""

from __future__ import annotations

import importlib
import os
from typing import Any, Callable

__all__ = ["kernel", "of", "available", "missing_because", "reference", "before_numba"]

_why = ""
try:
    if os.environ.get("SUPERFACETS_NATIVE", "1").strip() in ("0", "no", "false", "off"):
        _why = "turned off (SUPERFACETS_NATIVE=0)"
        raise ImportError(_why)
    _cxx = importlib.import_module("superfacets._kernels._cxx")
except ImportError:  # not built (no compiler at install time), or turned off
    _why = _why or "not built (no C++ compiler at install time?)"
    _cxx = None

_chosen: dict[str, Callable[..., Any]] = {}
_before: list[Callable[[], Any]] = []
#: the compiled kernels that sent a call to numba, and why (the last argument refused)
fallbacks: dict[str, str] = {}


def before_numba(fn: Callable[[], Any]) -> None:
    """Call ``fn`` once, just before the process's first numba kernel is imported (the
    command line's note that numba compiles on a first run: said only if it does)."""
    _before.append(fn)


def available() -> bool:
    """Whether the compiled kernels are built and in use."""
    return _cxx is not None


def limit_threads(n: int) -> int:
    """Let the compiled kernels use at most ``n`` threads (0: no limit, as
    ``NUMBA_NUM_THREADS`` or the CPUs allow), process-wide; returns the limit replaced
    (0 where the compiled kernels are not built)."""
    return int(_cxx.set_thread_limit(int(n))) if _cxx is not None else 0


def missing_because() -> str:
    """Why the compiled kernels are not in use ("" when they are)."""
    return "" if _cxx is not None else _why


def reference(path: str) -> Callable[..., Any]:
    """The numba kernel ``"module.name"`` of :mod:`superfacets._kernels` (imports numba)."""
    while _before:
        try:
            hook = _before.pop()
        except IndexError:  # another thread took the last one
            break
        hook()
    module, name = path.split(".")
    return getattr(importlib.import_module(f"superfacets._kernels.{module}"), name)


def kernel(path: str) -> Callable[..., Any]:
    """The kernel ``"module.name"``: compiled where built, numba otherwise (or for the
    argument types the compiled one does not take)."""
    found = _chosen.get(path)
    if found is not None:
        return found
    compiled = getattr(_cxx, path.split(".")[1], None) if _cxx is not None else None
    if compiled is None:
        found = reference(path)
    else:
        mismatch = _cxx.Mismatch

        def found(*args, **kwargs):
            try:
                return compiled(*args, **kwargs)
            except mismatch as exc:  # another dtype or layout: the numba kernel takes them all
                fallbacks[path] = str(exc)
                return reference(path)(*args, **kwargs)
            except TypeError as exc:  # a scalar of another type
                if "incompatible function arguments" not in str(exc):
                    raise
                fallbacks[path] = "arguments"
                return reference(path)(*args, **kwargs)

        found.__name__ = found.__qualname__ = path.split(".")[1]
        found.__doc__ = f"The compiled ``{path}`` (numba's for other argument types)."
    _chosen[path] = found
    return found


class of:
    """The kernels of one module as attributes (``of("expand").merge_some``), each
    chosen by :func:`kernel` on first use."""

    def __init__(self, module: str):
        self._module = module

    def __getattr__(self, name: str) -> Callable[..., Any]:
        if name.startswith("__"):
            raise AttributeError(name)
        return kernel(f"{self._module}.{name}")
