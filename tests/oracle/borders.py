"""The superfacet graph's borders, in numba (private kernel of
:func:`superfacets.graph.adjacency.superfacet_graph`): the crossing adjacencies grouped
by the pair of labels they join.
"""

import numpy as np
from numba import njit


@njit(cache=True, error_model="numpy", nogil=True)
def label_pairs(labels, pairs, k, inv):
    """The distinct label pairs ``lo * k + hi`` (``lo < hi``, the labels of the two
    elements of each row of ``pairs``), ascending, returned; ``inv[c]``: the place of
    row ``c``'s among them. ``np.unique(lo * k + hi, return_inverse=True)``, by a
    counting sort on ``lo`` and each ``lo``'s distinct ``hi`` sorted."""
    m = pairs.shape[0]
    lo = np.empty(m, dtype=np.int64)
    hi = np.empty(m, dtype=np.int64)
    start = np.zeros(k + 1, dtype=np.int64)
    for c in range(m):
        a, b = labels[pairs[c, 0]], labels[pairs[c, 1]]
        if a > b:
            a, b = b, a
        lo[c] = a
        hi[c] = b
        start[a + 1] += 1
    for s in range(k):
        start[s + 1] += start[s]
    fill = start[:k].copy()
    order = np.empty(m, dtype=np.int64)
    for c in range(m):
        order[fill[lo[c]]] = c
        fill[lo[c]] += 1
    stamp = np.full(k, -1, dtype=np.int64)
    slot = np.empty(k, dtype=np.int64)
    seen = np.empty(k, dtype=np.int64)
    key = np.empty(m, dtype=np.int64)
    e = 0
    for s in range(k):
        ns = 0
        for t in range(start[s], start[s + 1]):
            h = hi[order[t]]
            if stamp[h] != s:
                stamp[h] = s
                seen[ns] = h
                ns += 1
        part = np.sort(seen[:ns])
        for j in range(ns):
            slot[part[j]] = e + j
            key[e + j] = s * k + part[j]
        e += ns
        for t in range(start[s], start[s + 1]):
            inv[order[t]] = slot[hi[order[t]]]
    return key[:e].copy()
