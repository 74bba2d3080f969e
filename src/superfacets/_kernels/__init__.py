"""Kernels, one module per concept; private.

Each kernel is written in numba here and, for the default runs, again in C++
(``cxx/``, the module ``_cxx`` built by ``pip install``: the same operations in the
same order, tested bit for bit); :mod:`.native` gives the compiled one where built
and the numba one otherwise, so that a default run loads no numba.

Contiguous arrays and scalars in, preallocated arrays out; nothing here
validates its input. Callers name a kernel by module and function
(``native.kernel("expand.expand_many")``); the modules are named like the
``method/`` and ``elements/`` modules they serve; ``codes`` holds the status
codes without importing numba; ``heap`` is shared by the numba searches and the
VSA baseline's kernels.
"""
