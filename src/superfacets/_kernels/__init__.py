"""Kernels: the compiled core (private).

One implementation of each kernel, in C++ (``cxx/``, one source file per concept, the
module ``_cxx`` built by ``pip install`` through CMake and nanobind); :mod:`.native`
hands them to the rest of the package by module and function
(``native.kernel("expand.expand_many")``); ``codes`` holds the expansion kernels'
modes and status codes. Contiguous arrays and scalars in, preallocated arrays out:
callers validate, cast and allocate; a kernel refuses any other dtype or layout.
The reference kernels (numba) that keep them honest are in ``tests/oracle``.
"""
