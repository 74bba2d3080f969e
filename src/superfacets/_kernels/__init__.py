"""numba kernels, one module per concept; private.

Contiguous arrays and scalars in, preallocated arrays out; nothing here
validates its input. Each kernel module is imported only by the public module
that wraps it (and kernel modules by each other): ``expand`` (bounded
expansions, record merging) by :mod:`superfacets.classify` and its buffers
:mod:`superfacets.expansion` (and :mod:`superfacets.warmup`, which only
touches it); ``exact`` by :mod:`superfacets.classify`; ``update`` by
:mod:`superfacets.passes`; ``farthest`` and ``flood`` by
:mod:`superfacets.initialization`; ``geometry`` by :mod:`superfacets.mesh`;
``heap`` by ``exact`` and the VSA baseline's kernels; ``hierarchy`` (the
greedy merges of the levels) by :mod:`superfacets.hierarchy`.
"""
