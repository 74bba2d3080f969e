"""Felzenszwalb-Huttenlocher graph segmentation, in numba (private kernel of
:mod:`superfacets.evaluation.baselines.graph_segmentation`).

Union-find with union by rank and path compression; edges taken in the given
order (sorted by weight), then small components merged along the same order.
"""

import numpy as np
from numba import njit

from .connectivity import find as _find


@njit(cache=True, inline="always")
def _join(parent, rank, size, a, b):
    if rank[a] > rank[b]:
        parent[b] = a
        size[a] += size[b]
        return a
    parent[a] = b
    size[b] += size[a]
    if rank[a] == rank[b]:
        rank[b] += 1
    return b


@njit(cache=True)
def felzenszwalb(n, lo, hi, w, order, k_thresh, min_size, labels):
    """Fill ``labels`` with the root of each element; return the number of segments.

    ``order`` sorts the edges ``(lo, hi)`` by weight ``w``; an edge joins two
    components when its weight is at most both internal thresholds
    ``Int(C) + k / |C|`` (Felzenszwalb and Huttenlocher 2004, eq. 5); then
    every edge (same order) joins components smaller than ``min_size``.
    """
    parent = np.arange(n)
    rank = np.zeros(n, dtype=np.int64)
    size = np.ones(n, dtype=np.int64)
    thresh = np.full(n, k_thresh)
    count = n
    for t in order:
        a = _find(parent, lo[t])
        b = _find(parent, hi[t])
        if a != b and w[t] <= thresh[a] and w[t] <= thresh[b]:
            r = _join(parent, rank, size, a, b)
            thresh[r] = w[t] + k_thresh / size[r]
            count -= 1
    for t in order:
        a = _find(parent, lo[t])
        b = _find(parent, hi[t])
        if a != b and (size[a] < min_size or size[b] < min_size):
            _join(parent, rank, size, a, b)
            count -= 1
    for i in range(n):
        labels[i] = _find(parent, i)
    return count
