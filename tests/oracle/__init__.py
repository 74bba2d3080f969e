"""The reference kernels (numba): the oracle that keeps the compiled kernels honest.

The package runs one implementation of each kernel, the compiled one
(``superfacets._kernels._cxx``, C++). Each module here holds the numba kernels that the
compiled ones were written from, the same operations in the same order, so that
``tests/kernels/test_native.py`` can check every compiled kernel against its reference bit for
bit, on the inputs of real runs. They need numba (the ``test`` extra), never the package.

:func:`reference` gives the numba kernel that the package's ``native.kernel(path)``
call would run compiled.
"""

from __future__ import annotations

import importlib
from typing import Any, Callable

__all__ = ["reference", "RENAMED"]

#: the paths by which the package calls a kernel whose reference lives elsewhere here
RENAMED = {"expand.flood": "flood.flood"}


def reference(path: str) -> Callable[..., Any]:
    """The numba kernel ``"module.name"`` of this package (imports numba): the reference
    of the compiled kernel that the package calls by that path."""
    module, name = RENAMED.get(path, path).split(".")
    return getattr(importlib.import_module(f"{__name__}.{module}"), name)
