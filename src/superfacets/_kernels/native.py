"""The compiled kernels (private): ``superfacets._kernels._cxx``, C++ built by ``pip install``.

Every kernel of every run (segment, the content-adaptive level, coarse-to-fine, the
hierarchy, tiles, the evaluation and the baselines that are not GPL) is compiled ahead
of time, once, at install: no compiler and no just-in-time compilation at run time, so
the first run of any option is as fast as the next. The reference kernels they were
written from (numba) live in the tests (``tests/oracle``), which check each compiled
kernel against its reference bit for bit.

:func:`kernel` gives the compiled callable for ``"source.name"``: one name in three places,
the C++ source that defines it (``_kernels/cxx/source.cpp``, bound as the submodule
``_cxx.source``), the address the package calls it by, and its reference
(``tests/oracle/source.py``). A kernel takes exactly the
dtypes and layouts its callers pass and never converts: anything else raises its
``Mismatch`` (a :class:`TypeError`) before touching any array, a defect of the caller.
"""

from __future__ import annotations

import importlib
from typing import Any, Callable

from ..errors import KernelsMissingError

__all__ = ["kernel", "of", "available", "missing_because", "limit_threads", "require",
           "sources_digest"]

_why = ""
try:
    _cxx = importlib.import_module("superfacets._kernels._cxx")
except ImportError as exc:  # a source tree used without building it
    _why = f"not built ({exc})"
    _cxx = None

_chosen: dict[str, Callable[..., Any]] = {}


def available() -> bool:
    """Whether the compiled kernels are built."""
    return _cxx is not None


def missing_because() -> str:
    """Why the compiled kernels cannot be used ("" when they can)."""
    return "" if _cxx is not None else _why


def sources_digest() -> str:
    """The digest of the C++ sources the kernels were built from (CMakeLists.txt writes it
    beside the module); "" where it is not there."""
    from pathlib import Path

    if _cxx is None:
        return ""
    path = Path(_cxx.__file__).with_name("_cxx_sources.txt")
    return path.read_text().strip() if path.is_file() else ""


def require():
    """The compiled module; :class:`KernelsMissingError` (one line) where it is not built."""
    if _cxx is None:
        raise KernelsMissingError(
            f"superfacets' compiled kernels are {_why}: install the package "
            "(pip install . in a clone, with a C++17 compiler), not its source folder alone")
    return _cxx


def limit_threads(n: int) -> int:
    """Let the compiled kernels use at most ``n`` threads (0: no limit, as
    ``SUPERFACETS_KERNEL_THREADS`` or the CPUs allow), process-wide; returns the limit
    replaced (0 where the kernels are not built)."""
    return int(_cxx.set_thread_limit(int(n))) if _cxx is not None else 0


def kernel(path: str) -> Callable[..., Any]:
    """The compiled kernel ``"source.name"``: ``name`` defined in ``_kernels/cxx/source.cpp``
    (bound as the submodule ``_cxx.source``), its reference ``tests/oracle/source.py``."""
    found = _chosen.get(path)
    if found is None:
        source, _, name = path.partition(".")
        found = getattr(getattr(require(), source, None), name, None)
        if found is None:
            raise AttributeError(f"no compiled kernel {path!r} (src/superfacets/_kernels/cxx/"
                                 f"{source}.cpp binds none of that name)")
        _chosen[path] = found
    return found


class of:
    """The kernels of one module as attributes (``of("expand").merge_some``)."""

    def __init__(self, module: str):
        self._module = module

    def __getattr__(self, name: str) -> Callable[..., Any]:
        if name.startswith("__"):
            raise AttributeError(name)
        return kernel(f"{self._module}.{name}")
