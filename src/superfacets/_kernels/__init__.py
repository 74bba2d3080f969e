"""numba kernels, one module per concept; private.

Contiguous arrays and scalars in, preallocated arrays out; nothing here
validates its input. Each kernel module is imported only by the public module
that wraps it (and kernel modules by each other): ``expand`` (bounded
expansions, record merging) by :mod:`superfacets.method.classify` and its buffers
:mod:`superfacets.method.expansion` (and :mod:`superfacets._runtime.warmup`, which only
touches it); ``exact`` by :mod:`superfacets.method.classify`; ``update`` by
:mod:`superfacets.method.passes`; ``farthest`` and ``flood`` by
:mod:`superfacets.method.initialization`; ``geometry`` by :mod:`superfacets.inputs.mesh`;
``heap`` by ``exact`` and the VSA baseline's kernels; ``hierarchy`` (the
greedy merges of the levels) by :mod:`superfacets.graph.hierarchy`.
"""
